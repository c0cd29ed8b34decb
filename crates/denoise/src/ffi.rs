//! The only `unsafe` of the crate: OIDN's C API (`oidn.h`, 2.x) opened with `dlopen` and
//! wrapped in owners that release what they create.
//!
//! The functions are declared by hand, only those used, with the C types of `oidn.h`:
//! handles are opaque pointers, enums are `c_int`, sizes `size_t`. Every call goes through a
//! [`Device`] or [`Filter`] that holds a live handle and keeps the library loaded (the
//! [`Api`] is shared through an `Arc`), so no symbol outlives its library.

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::Path;
use std::sync::Arc;

type DeviceHandle = *mut c_void;
type FilterHandle = *mut c_void;

/// `OIDN_DEVICE_TYPE_CPU`.
const DEVICE_TYPE_CPU: c_int = 1;
/// `OIDN_FORMAT_FLOAT3`.
const FORMAT_FLOAT3: c_int = 3;
/// `OIDN_ERROR_NONE`.
const ERROR_NONE: c_int = 0;

/// The symbols of OIDN's C API that aperture calls, resolved once from the library.
struct Api {
    new_device: unsafe extern "C" fn(c_int) -> DeviceHandle,
    commit_device: unsafe extern "C" fn(DeviceHandle),
    get_device_error: unsafe extern "C" fn(DeviceHandle, *mut *const c_char) -> c_int,
    get_device_int: unsafe extern "C" fn(DeviceHandle, *const c_char) -> c_int,
    release_device: unsafe extern "C" fn(DeviceHandle),
    new_filter: unsafe extern "C" fn(DeviceHandle, *const c_char) -> FilterHandle,
    set_shared_filter_image: unsafe extern "C" fn(
        FilterHandle,
        *const c_char,
        *mut c_void,
        c_int,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    set_filter_bool: unsafe extern "C" fn(FilterHandle, *const c_char, bool),
    set_filter_int: unsafe extern "C" fn(FilterHandle, *const c_char, c_int),
    commit_filter: unsafe extern "C" fn(FilterHandle),
    execute_filter: unsafe extern "C" fn(FilterHandle),
    release_filter: unsafe extern "C" fn(FilterHandle),
    /// Kept last: dropped after nothing can call the pointers above.
    _lib: libloading::Library,
}

/// Opens `name` (a path, or a bare file name for the system's search path) and resolves the
/// API; the error is `dlopen`'s or `dlsym`'s message.
fn open(name: &Path) -> Result<Api, String> {
    // SAFETY: loading runs the library's initialisers; OIDN's (and TBB's) are plain C++
    // static constructors with no precondition on the caller.
    let lib = unsafe { libloading::Library::new(name) }.map_err(|e| e.to_string())?;
    macro_rules! sym {
        ($name:literal) => {
            // SAFETY: the type given at each use is the function's signature in `oidn.h` 2.x
            // (pointer-sized handles, `int` enums, `size_t` sizes, C `bool`).
            *unsafe { lib.get(concat!($name, "\0").as_bytes()) }.map_err(|e| e.to_string())?
        };
    }
    Ok(Api {
        new_device: sym!("oidnNewDevice"),
        commit_device: sym!("oidnCommitDevice"),
        get_device_error: sym!("oidnGetDeviceError"),
        get_device_int: sym!("oidnGetDeviceInt"),
        release_device: sym!("oidnReleaseDevice"),
        new_filter: sym!("oidnNewFilter"),
        set_shared_filter_image: sym!("oidnSetSharedFilterImage"),
        set_filter_bool: sym!("oidnSetFilterBool"),
        set_filter_int: sym!("oidnSetFilterInt"),
        commit_filter: sym!("oidnCommitFilter"),
        execute_filter: sym!("oidnExecuteFilter"),
        release_filter: sym!("oidnReleaseFilter"),
        _lib: lib,
    })
}

fn cstr(s: &str) -> CString {
    CString::new(s).unwrap_or_default()
}

/// A committed OIDN CPU device of a loaded library.
pub(crate) struct Device {
    api: Arc<Api>,
    handle: DeviceHandle,
}

impl Device {
    /// Loads the library at `name` and makes a CPU device; `Err` holds why, in words.
    pub(crate) fn open(name: &Path) -> Result<Self, String> {
        let api = Arc::new(open(name)?);
        // SAFETY: `oidnNewDevice` takes any device type and returns null on failure.
        let handle = unsafe { (api.new_device)(DEVICE_TYPE_CPU) };
        if handle.is_null() {
            return Err("oidnNewDevice(CPU) returned no device".into());
        }
        let device = Device { api, handle };
        // SAFETY: `handle` is a live device.
        unsafe { (device.api.commit_device)(device.handle) };
        device.check()?;
        Ok(device)
    }

    /// The library's version, `major * 10000 + minor * 100 + patch` (OIDN's `version`).
    pub(crate) fn version(&self) -> i32 {
        let name = cstr("version");
        // SAFETY: live device, NUL-terminated parameter name.
        unsafe { (self.api.get_device_int)(self.handle, name.as_ptr()) }
    }

    /// The device's pending error, cleared, as `Err(message)`.
    pub(crate) fn check(&self) -> Result<(), String> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: live device; OIDN writes a pointer to a string it owns (or null), valid
        // until the next call on the device, and it is copied at once.
        let code = unsafe { (self.api.get_device_error)(self.handle, &mut message) };
        if code == ERROR_NONE {
            return Ok(());
        }
        let text = if message.is_null() {
            String::new()
        } else {
            // SAFETY: non-null, NUL-terminated, owned by the device until the next call.
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        Err(format!("OIDN error {code}: {text}"))
    }
}

// SAFETY: OIDN's API is thread-safe ("All API calls are thread-safe, but operations that use
// the same device will be serialized", OIDN 2 documentation, "Open Image Denoise API"); the
// handle is an opaque pointer to the library's reference-counted device object, and `Api`
// holds only function pointers and the library handle.
unsafe impl Send for Device {}
// SAFETY: as for `Send`: calls on one device from several threads are serialised by OIDN.
unsafe impl Sync for Device {}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: the handle is live and released once; filters borrow the device, so none
        // is left.
        unsafe { (self.api.release_device)(self.handle) };
    }
}

/// One filter run: its input images, its output and its parameters.
pub(crate) struct Run<'a> {
    /// The filter type (`"RT"`).
    pub kind: &'a str,
    /// Width of every image.
    pub width: usize,
    /// Height of every image.
    pub height: usize,
    /// Input images by OIDN name (`color`, `albedo`, `normal`), packed RGB rows.
    pub inputs: &'a [(&'a str, &'a [[f32; 3]])],
    /// Boolean parameters (`hdr`, `cleanAux`).
    pub bools: &'a [(&'a str, bool)],
    /// Integer parameters (`quality`).
    pub ints: &'a [(&'a str, i32)],
}

impl Device {
    /// Runs one filter into `output` (the image OIDN calls `output`); `Err` is why, in words.
    pub(crate) fn run(&self, run: &Run<'_>, output: &mut [[f32; 3]]) -> Result<(), String> {
        let n = run.width * run.height;
        if output.len() != n || run.inputs.iter().any(|(_, px)| px.len() != n) {
            return Err(format!("images are not all {}x{}", run.width, run.height));
        }
        let filter = Filter {
            device: self,
            handle: self.new_filter(run.kind)?,
        };
        let image = |name: &str, pixels: *mut c_void| {
            let name = cstr(name);
            // SAFETY: live filter; `pixels` points to `width * height` packed RGB floats
            // (lengths checked above; zero strides mean packed); OIDN keeps the pointer and
            // uses it only in `oidnExecuteFilter` below, while the borrows of `run` and
            // `output` hold the buffers in place. Inputs are only read.
            unsafe {
                (self.api.set_shared_filter_image)(
                    filter.handle,
                    name.as_ptr(),
                    pixels,
                    FORMAT_FLOAT3,
                    run.width,
                    run.height,
                    0,
                    0,
                    0,
                )
            }
        };
        for (name, pixels) in run.inputs {
            image(name, pixels.as_ptr().cast_mut().cast());
        }
        image("output", output.as_mut_ptr().cast());
        for (name, value) in run.bools {
            let name = cstr(name);
            // SAFETY: live filter, NUL-terminated name.
            unsafe { (self.api.set_filter_bool)(filter.handle, name.as_ptr(), *value) };
        }
        for (name, value) in run.ints {
            let name = cstr(name);
            // SAFETY: live filter, NUL-terminated name.
            unsafe { (self.api.set_filter_int)(filter.handle, name.as_ptr(), *value) };
        }
        // SAFETY: live filter whose images are set to the live buffers above.
        unsafe { (self.api.commit_filter)(filter.handle) };
        self.check()?;
        // SAFETY: as above; the call returns once the output is written (CPU device, sync).
        unsafe { (self.api.execute_filter)(filter.handle) };
        self.check()
    }

    /// A new filter handle of `kind`.
    fn new_filter(&self, kind: &str) -> Result<FilterHandle, String> {
        let name = cstr(kind);
        // SAFETY: live device, NUL-terminated type name; null on failure.
        let handle = unsafe { (self.api.new_filter)(self.handle, name.as_ptr()) };
        self.check()?;
        if handle.is_null() {
            return Err(format!("oidnNewFilter({kind}) returned no filter"));
        }
        Ok(handle)
    }
}

/// A filter handle, released when dropped.
struct Filter<'a> {
    device: &'a Device,
    handle: FilterHandle,
}

impl Drop for Filter<'_> {
    fn drop(&mut self) {
        // SAFETY: live handle, released once.
        unsafe { (self.device.api.release_filter)(self.handle) };
    }
}
