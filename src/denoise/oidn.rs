//! The binding to Intel Open Image Denoise 2.x's C API (`OpenImageDenoise/oidn.h`), loaded at run
//! time with libloading: a device, and one `RT` filter per call over caller-owned images.
//!
//! This is the crate's only unsafe code besides the sky's cache prefetch hint
//! (`sky/prefetch.rs`): calling C functions found by name in a shared library cannot be checked
//! by the compiler. The safe wrapper ([`Device`]) keeps the invariants the C API
//! needs: the function pointers come from libraries that are never unloaded, every image handed to
//! OIDN has exactly `width * height * 3` floats and outlives the filter that reads it, the device
//! is used by one thread at a time (it lives in a `Mutex` in [`super::Denoiser`]), and errors are
//! read back with `oidnGetDeviceError` on the thread that caused them.
#![allow(
    unsafe_code,
    reason = "FFI to a C library loaded at run time; see the module documentation"
)]

use std::ffi::{CStr, c_char, c_void};
use std::mem::ManuallyDrop;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use libloading::Library;

/// The soname of OIDN 2.x's main library.
pub(super) const LIBRARY_NAME: &str = "libOpenImageDenoise.so.2";
/// TBB, which the CPU device module needs.
const TBB_NAME: &str = "libtbb.so.12";
/// The prefix of the core library's versioned file name (`libOpenImageDenoise_core.so.2.5.1`).
const CORE_PREFIX: &str = "libOpenImageDenoise_core.so.2";

// Values of the C enums (OIDNDeviceType, OIDNFormat, OIDNError) in oidn.h; they are `int` in the
// C ABI.
const DEVICE_TYPE_CPU: i32 = 1;
const FORMAT_FLOAT3: i32 = 3;
const ERROR_NONE: i32 = 0;
const ERROR_CANCELLED: i32 = 6;

type RawDevice = *mut c_void;
type RawFilter = *mut c_void;
type ProgressFn = unsafe extern "C" fn(user: *mut c_void, progress: f64) -> bool;

/// The C functions used, copied out of the library (valid for the process's lifetime because the
/// library is never unloaded).
#[derive(Clone, Copy)]
struct Functions {
    new_device: unsafe extern "C" fn(i32) -> RawDevice,
    commit_device: unsafe extern "C" fn(RawDevice),
    release_device: unsafe extern "C" fn(RawDevice),
    get_device_int: unsafe extern "C" fn(RawDevice, *const c_char) -> i32,
    get_device_error: unsafe extern "C" fn(RawDevice, *mut *const c_char) -> i32,
    new_filter: unsafe extern "C" fn(RawDevice, *const c_char) -> RawFilter,
    set_shared_filter_image: unsafe extern "C" fn(
        RawFilter,
        *const c_char,
        *mut c_void,
        i32,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    set_filter_bool: unsafe extern "C" fn(RawFilter, *const c_char, bool),
    set_filter_int: unsafe extern "C" fn(RawFilter, *const c_char, i32),
    set_filter_progress_monitor_function:
        unsafe extern "C" fn(RawFilter, Option<ProgressFn>, *mut c_void),
    commit_filter: unsafe extern "C" fn(RawFilter),
    execute_filter: unsafe extern "C" fn(RawFilter),
    release_filter: unsafe extern "C" fn(RawFilter),
}

/// Loads OIDN from `dir` (which holds [`LIBRARY_NAME`]), by full paths only (never the system
/// loader's search). TBB and the core library found there are loaded first: the wheel's libraries find each other through `RPATH $ORIGIN/../lib`,
/// which only works in a directory named `lib`, and the dynamic linker reuses an already loaded
/// library for a dependency of the same soname. The CPU device module is loaded by OIDN itself
/// from the core library's directory.
///
/// The libraries are never unloaded: OIDN's TBB thread pool outlives any one device, and
/// unloading code its threads may still run would crash.
fn open(dir: &Path) -> Result<Functions, String> {
    let load = |path: &Path| {
        // SAFETY: loading runs the library's initialisers; OIDN's and TBB's only set up their
        // own state.
        unsafe { Library::new(path) }
            .map(ManuallyDrop::new)
            .map_err(|e| loader_error(&e))
    };
    let tbb = dir.join(TBB_NAME);
    if tbb.is_file() {
        load(&tbb)?;
    }
    if let Some(core) = find_core(dir) {
        load(&core)?;
    }
    let main = load(&dir.join(LIBRARY_NAME))?;
    Ok(Functions {
        new_device: symbol(&main, "oidnNewDevice")?,
        commit_device: symbol(&main, "oidnCommitDevice")?,
        release_device: symbol(&main, "oidnReleaseDevice")?,
        get_device_int: symbol(&main, "oidnGetDeviceInt")?,
        get_device_error: symbol(&main, "oidnGetDeviceError")?,
        new_filter: symbol(&main, "oidnNewFilter")?,
        set_shared_filter_image: symbol(&main, "oidnSetSharedFilterImage")?,
        set_filter_bool: symbol(&main, "oidnSetFilterBool")?,
        set_filter_int: symbol(&main, "oidnSetFilterInt")?,
        set_filter_progress_monitor_function: symbol(
            &main,
            "oidnSetFilterProgressMonitorFunction",
        )?,
        commit_filter: symbol(&main, "oidnCommitFilter")?,
        execute_filter: symbol(&main, "oidnExecuteFilter")?,
        release_filter: symbol(&main, "oidnReleaseFilter")?,
    })
}

/// The function `name` of `library`, as the function pointer type `T` (inferred from the
/// [`Functions`] field it is stored in, which has the signature oidn.h declares).
fn symbol<T: Copy>(library: &Library, name: &str) -> Result<T, String> {
    // SAFETY: `T` is the C signature of `name` (see above); the library is never unloaded, so
    // the pointer stays valid.
    unsafe { library.get::<T>(name.as_bytes()) }
        .map(|s| *s)
        .map_err(|e| format!("{} (is this Open Image Denoise 2.x?)", loader_error(&e)))
}

/// libloading's error with the loader's own message (`dlerror()`), which its `Display` leaves
/// to the error's source.
fn loader_error(e: &libloading::Error) -> String {
    match std::error::Error::source(e) {
        Some(source) => format!("{e}: {source}"),
        None => e.to_string(),
    }
}

/// The core library in `dir`, whose file name carries the full version.
fn find_core(dir: &Path) -> Option<std::path::PathBuf> {
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(CORE_PREFIX))
        })
        .collect();
    names.sort();
    names.pop()
}

/// Why a filter run failed.
pub(super) enum RunError {
    /// The progress callback saw the cancel flag.
    Cancelled,
    /// OIDN reported an error (its message).
    Oidn(String),
}

/// The images of one run, each `width * height` RGB float triples.
pub(super) struct Images<'a> {
    pub width: usize,
    pub height: usize,
    pub color: &'a [f32],
    pub albedo: Option<&'a [f32]>,
    pub normal: Option<&'a [f32]>,
}

/// A committed OIDN CPU device.
pub(super) struct Device {
    f: Functions,
    raw: RawDevice,
    version: i32,
}

// SAFETY: OIDN devices are not tied to the thread that created them; `Denoiser` keeps the device
// in a Mutex, so one thread at a time uses it.
unsafe impl Send for Device {}

impl Device {
    /// Loads the library (see [`open`]) and creates and commits a CPU device.
    pub(super) fn new(dir: &Path) -> Result<Device, String> {
        let f = open(dir)?;
        // SAFETY: the functions come from a loaded OIDN 2.x; a null device is checked before use
        // (oidnGetDeviceError accepts null for errors of device creation).
        unsafe {
            let raw = (f.new_device)(DEVICE_TYPE_CPU);
            if raw.is_null() {
                let (_, message) = take_error(&f, raw);
                return Err(format!("could not create a CPU device: {message}"));
            }
            let mut device = Device { f, raw, version: 0 };
            (f.commit_device)(raw);
            device
                .check()
                .map_err(|message| format!("could not initialise the CPU device: {message}"))?;
            device.version = (f.get_device_int)(raw, c"version".as_ptr());
            Ok(device)
        }
    }

    /// OIDN's version as `major * 10000 + minor * 100 + patch`.
    pub(super) fn version(&self) -> i32 {
        self.version
    }

    /// The first error OIDN stored for this device and thread since the last check, if any.
    fn check(&self) -> Result<(), String> {
        // SAFETY: `raw` is a live device.
        match unsafe { take_error(&self.f, self.raw) } {
            (ERROR_NONE, _) => Ok(()),
            (_, message) => Err(message),
        }
    }

    /// Runs the `RT` filter (HDR colour) with the given quality on `images` and returns the
    /// denoised colour. `cancel` is polled by OIDN's progress monitor; when it is set, OIDN stops
    /// and the run ends with [`RunError::Cancelled`].
    pub(super) fn run(
        &mut self,
        images: &Images,
        quality: i32,
        cancel: &AtomicBool,
    ) -> Result<Vec<f32>, RunError> {
        let Images { width, height, .. } = *images;
        let len = width
            .checked_mul(height)
            .and_then(|p| p.checked_mul(3))
            .filter(|&n| n > 0)
            .ok_or_else(|| RunError::Oidn(format!("invalid size {width}×{height}")))?;
        let inputs = [
            (c"color", Some(images.color)),
            (c"albedo", images.albedo),
            (c"normal", images.normal),
        ];
        if inputs
            .iter()
            .any(|(_, image)| image.is_some_and(|i| i.len() != len))
        {
            return Err(RunError::Oidn("image of the wrong length".into()));
        }
        let mut output = vec![0.0f32; len];
        // Clear an error a previous run on this thread may have left.
        let _ = self.check();
        let f = self.f;
        // SAFETY: the device is live; the filter is released before this block ends, while
        // every image it points to (the inputs, borrowed for the call, and `output`) and the
        // cancel flag are still alive; each image has `width * height` FLOAT3 pixels, stored
        // contiguously (strides 0 = computed by OIDN). OIDN only reads the inputs, so casting
        // their pointers to `*mut` for the C signature is sound.
        unsafe {
            let filter = (f.new_filter)(self.raw, c"RT".as_ptr());
            if filter.is_null() {
                return Err(RunError::Oidn(self.check().err().unwrap_or_default()));
            }
            let set_image = |name: &CStr, ptr: *mut c_void| {
                (f.set_shared_filter_image)(
                    filter,
                    name.as_ptr(),
                    ptr,
                    FORMAT_FLOAT3,
                    width,
                    height,
                    0,
                    0,
                    0,
                );
            };
            for (name, image) in inputs {
                if let Some(image) = image {
                    set_image(name, image.as_ptr().cast_mut().cast());
                }
            }
            set_image(c"output", output.as_mut_ptr().cast());
            (f.set_filter_bool)(filter, c"hdr".as_ptr(), true);
            (f.set_filter_int)(filter, c"quality".as_ptr(), quality);
            (f.set_filter_progress_monitor_function)(
                filter,
                Some(progress),
                std::ptr::from_ref(cancel).cast_mut().cast(),
            );
            (f.commit_filter)(filter);
            let committed = take_error(&f, self.raw);
            if committed.0 == ERROR_NONE {
                (f.execute_filter)(filter);
            }
            (f.release_filter)(filter);
            let (code, message) = if committed.0 == ERROR_NONE {
                take_error(&f, self.raw)
            } else {
                committed
            };
            match code {
                ERROR_NONE => Ok(output),
                ERROR_CANCELLED => Err(RunError::Cancelled),
                _ => Err(RunError::Oidn(message)),
            }
        }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: `raw` is a live device, released once.
        unsafe { (self.f.release_device)(self.raw) }
    }
}

/// OIDN's progress monitor: returns false (stop) once the cancel flag is set. `user` is the
/// `&AtomicBool` given to `oidnSetFilterProgressMonitorFunction`.
unsafe extern "C" fn progress(user: *mut c_void, _done: f64) -> bool {
    // SAFETY: `Device::run` passes a reference to an AtomicBool that outlives the filter.
    let cancel = unsafe { &*user.cast::<AtomicBool>() };
    !cancel.load(Ordering::Relaxed)
}

/// Takes (and clears) the first stored error of `device` (or of device creation, when null) on
/// this thread: its code and message.
///
/// # Safety
/// `device` is null or a live device of the library `f` came from.
unsafe fn take_error(f: &Functions, device: RawDevice) -> (i32, String) {
    let mut message: *const c_char = std::ptr::null();
    // SAFETY: per this function's contract; the message, when not null, is a NUL-terminated
    // string valid until the next OIDN call, and is copied at once.
    unsafe {
        let code = (f.get_device_error)(device, &raw mut message);
        let text = if message.is_null() {
            format!("error code {code}")
        } else {
            CStr::from_ptr(message).to_string_lossy().into_owned()
        };
        (code, text)
    }
}
