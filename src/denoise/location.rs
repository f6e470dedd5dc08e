//! Where the OIDN library is looked for, and whether a folder or file there may be loaded.
//!
//! Loading a shared library runs its code, so rondo looks only in two places: the folder named
//! by `RONDO_OIDN_DIR`, or else `.oidn/lib` in the project rondo was built from (where
//! `scripts/fetch-oidn.sh` puts it). Never in folders above the executable: a binary below the
//! system's temporary folder would load a `.oidn/lib` any local user can create there. A folder
//! or library is refused, as ssh refuses a key file, when another user could change it: every
//! file loaded and every folder from it up to `/` must be owned by the caller or root and not
//! writable by group or others, but for folders above the library's own that have the sticky
//! bit (as `/tmp`), where others cannot rename or remove what they do not own.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

/// The folder `scripts/fetch-oidn.sh` fills: `.oidn/lib` in the project's root, where
/// `Cargo.toml` is.
const FETCHED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/.oidn/lib");

/// Where the library is looked for, given the value of `RONDO_OIDN_DIR`: that folder alone if
/// set (an explicit choice is never silently replaced by another copy), else [`FETCHED`].
pub(super) fn search_path(dir_variable: Option<&OsStr>) -> PathBuf {
    match dir_variable.filter(|d| !d.is_empty()) {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(FETCHED),
    }
}

/// Whether a file name is one of the libraries rondo or OIDN loads from the folder (OIDN's
/// main library, its core and device modules, TBB).
fn is_loaded(name: &OsStr) -> bool {
    let name = name.to_string_lossy();
    name.starts_with("libOpenImageDenoise") || name.starts_with("libtbb")
}

/// Checks that `dir` and the libraries in it may be loaded (see the module documentation) and
/// returns the folder with every symbolic link resolved, to load from, so that a link cannot be
/// changed between the check and the load. The error says which path is refused and why.
pub(super) fn trusted(dir: &Path) -> Result<PathBuf, String> {
    let real = dir
        .canonicalize()
        .map_err(|e| format!("{}: {e}", dir.display()))?;
    check_chain(&real)?;
    let entries = std::fs::read_dir(&real).map_err(|e| format!("{}: {e}", real.display()))?;
    for entry in entries {
        let path = entry
            .map_err(|e| format!("{}: {e}", real.display()))?
            .path();
        if !path.file_name().is_some_and(is_loaded) {
            continue;
        }
        let file = path
            .canonicalize()
            .map_err(|e| format!("{}: {e}", path.display()))?;
        check_one(&file, false)?;
        if let Some(parent) = file.parent() {
            check_chain(parent)?;
        }
    }
    Ok(real)
}

/// Checks the folder `dir` (a canonical path) and every folder above it.
fn check_chain(dir: &Path) -> Result<(), String> {
    for (i, folder) in dir.ancestors().enumerate() {
        check_one(folder, i > 0)?;
    }
    Ok(())
}

/// Checks one file or folder: owned by the caller or root, writable by no one else unless
/// `sticky_ok` and it has the sticky bit.
#[cfg(unix)]
fn check_one(path: &Path, sticky_ok: bool) -> Result<(), String> {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let caller = rustix::process::geteuid().as_raw();
    refusal(meta.uid(), meta.mode(), caller, sticky_ok).map_or(Ok(()), |why| {
        Err(format!("{}: refused: {why}", path.display()))
    })
}

/// Without Unix owners and modes there is nothing to check.
#[cfg(not(unix))]
fn check_one(_path: &Path, _sticky_ok: bool) -> Result<(), String> {
    Ok(())
}

/// Why a file or folder of owner `uid` and `mode` may not be trusted by user `caller`, if so.
fn refusal(uid: u32, mode: u32, caller: u32, sticky_ok: bool) -> Option<String> {
    const STICKY: u32 = 0o1000;
    const OTHERS_WRITE: u32 = 0o022;
    if uid != caller && uid != 0 {
        return Some(format!(
            "owned by user {uid}, not by you ({caller}) or root, who alone may provide code \
            rondo loads"
        ));
    }
    if mode & OTHERS_WRITE != 0 && !(sticky_ok && mode & STICKY != 0) {
        return Some(format!(
            "writable by others (mode {:o}), who could replace the code rondo loads",
            mode & 0o7777
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_search_path_is_the_variable_or_the_fetched_folder_only() {
        assert_eq!(
            search_path(Some(OsStr::new("/opt/oidn"))),
            Path::new("/opt/oidn")
        );
        let fetched = Path::new(env!("CARGO_MANIFEST_DIR")).join(".oidn/lib");
        assert_eq!(search_path(None), fetched);
        assert_eq!(search_path(Some(OsStr::new(""))), fetched);
    }

    #[test]
    fn owners_and_modes_are_judged_as_ssh_does() {
        let me = 1000;
        assert_eq!(refusal(me, 0o40755, me, false), None);
        assert_eq!(refusal(0, 0o40755, me, false), None);
        assert!(refusal(1001, 0o40755, me, false).is_some());
        assert!(refusal(me, 0o40775, me, false).is_some(), "group-writable");
        assert!(refusal(me, 0o40757, me, false).is_some(), "world-writable");
        assert!(
            refusal(0, 0o41777, me, false).is_some(),
            "sticky, the library's own"
        );
        assert_eq!(refusal(0, 0o41777, me, true), None, "sticky, above it");
        assert!(refusal(0, 0o40777, me, true).is_some(), "not sticky");
    }
}
