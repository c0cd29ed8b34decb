#!/usr/bin/env bash
# SPDX-License-Identifier: MIT OR Apache-2.0
# Counts the aarch64 instructions a command executes under qemu-aarch64 (issue 62: NEON against
# the scalar fallback, measured on an x86-64 machine), with our TCG plugin tools/cross/insn_count.c.
#
#   tools/cross/insn_count.sh AARCH64_PROGRAM [ARGS...]     prints "insns: N" on stderr
#
# The plugin is built into $CARGO_TARGET_DIR (or target/)/insn_count/ when missing or older than
# its source. Run the program on one thread (the counter is shared; see insn_count.c).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="${CARGO_TARGET_DIR:-$root/target}/insn_count"
so="$out/libinsn_count.so"
if [ ! -f "$so" ] || [ "$root/tools/cross/insn_count.c" -nt "$so" ]; then
    mkdir -p "$out"
    gcc -O2 -shared -fPIC -Wall -Wextra -o "$so" "$root/tools/cross/insn_count.c"
fi
exec qemu-aarch64 -plugin "$so" -d plugin -L /usr/aarch64-linux-gnu "$@"
