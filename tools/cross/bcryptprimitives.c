/* SPDX-License-Identifier: MIT OR Apache-2.0
 *
 * A stand-in for Windows' bcryptprimitives.dll, for running aperture.exe under Debian 12's
 * wine 8 in tools/cross/check.sh only (never shipped): Rust's standard library (1.78 on) takes
 * its random seeds from ProcessPrng in bcryptprimitives.dll, which wine provides only from
 * version 9. This one answers with RtlGenRandom (advapi32's SystemFunction036), which wine 8
 * has. Built with mingw-w64 and put beside the .exe, where Windows' DLL search looks first. */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length)
{
    while (length > 0) {
        ULONG n = length > 0x10000000 ? 0x10000000 : (ULONG)length;
        if (!SystemFunction036(data, n))
            return FALSE;
        data += n;
        length -= n;
    }
    return TRUE;
}
