//! Output files written atomically and safely, and the removal of their temporaries when the
//! process is stopped by a signal.
//!
//! Every file rondo writes (images, partials, CSV, charts, summaries) goes through
//! [`write_atomically`]: the bytes go to a temporary file in the output's directory, which is then
//! renamed over the output, so a reader sees the old file or the new one, never half of one.
//!
//! - The temporary is created exclusively (`O_CREAT | O_EXCL`, which never follows a symlink)
//!   under an unpredictable name, `.NAME.XXXXXX.tmp` with six random characters, retried on a
//!   clash. A symlink planted at a name another process could guess cannot redirect the write.
//! - The rename replaces whatever is at the output path. If that is a symlink, the link itself
//!   is replaced by the new file; the file it pointed to is not written (and may be outside the
//!   output's directory, which therefore cannot be made to change).
//! - On Unix the temporary is created with mode `0o666` less the umask, as `File::create`
//!   would, so the output gets the usual permissions rather than the owner-only ones of a
//!   temporary file; a regular file replaced passes its own permissions on to the new one.
//! - A temporary is removed when the write fails, and, once
//!   [`remove_temporaries_on_termination`] is installed, when SIGINT, SIGTERM or SIGHUP ends the
//!   process in the middle of a write: live temporaries are kept in a registry that the signal
//!   handler empties before it exits.

use std::ffi::OsString;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use tempfile::TempPath;

/// Exit status of a process ended by SIGINT, SIGTERM or SIGHUP (128 + SIGINT, as shells report
/// an interrupted command).
pub const EXIT_SIGNALLED: i32 = 130;

/// Paths of the temporaries being written. A path is added under the lock in the same step as
/// the file is created, and removed under the lock in the same step as it is renamed, so the
/// signal handler, which takes the lock and never gives it back, sees every temporary on disk.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// What the first termination signal does instead of exiting, if set (a graceful stop).
type OnSignal = Box<dyn FnOnce() + Send>;
static ON_SIGNAL: Mutex<Option<OnSignal>> = Mutex::new(None);

fn lock<T>(m: &'static Mutex<T>) -> MutexGuard<'static, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Writes a file atomically: `encode` writes to a temporary file in the same directory, which is
/// then synced and renamed over `path`, so a reader never sees a half-written file and a failed
/// write leaves the old one in place. See the module documentation for the temporary's name
/// and what happens to a symlink at `path`.
pub fn write_atomically(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    write_file(path, true, encode)
}

/// Writes `bytes` to `path` with [`write_atomically`].
pub fn write_bytes(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomically(path, |out| out.write_all(bytes))
}

/// [`write_atomically`], with the sync before the rename only if `sync` (live images replaced
/// within moments skip it).
pub fn write_file(
    path: &Path,
    sync: bool,
    encode: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let Some(name) = path.file_name() else {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{}: not a file name", path.display()),
        ));
    };
    let mut prefix = OsString::from(".");
    prefix.push(name);
    prefix.push(".");
    let (file, temporary) = Temporary::create(dir, &prefix)?;
    // A file replaced keeps its permissions (a scene file the viewer writes a camera into, an
    // image kept private); a symbolic link there is replaced as a new file would be.
    if let Ok(old) = std::fs::symlink_metadata(path)
        && old.is_file()
    {
        file.set_permissions(old.permissions())?;
    }
    let mut out = BufWriter::new(file);
    encode(&mut out)?;
    out.flush()?;
    if sync {
        out.get_ref().sync_all()?;
    }
    drop(out);
    temporary.persist(path)
}

/// A temporary file on disk, listed in [`LIVE`]; removed when dropped unless renamed.
struct Temporary(Option<TempPath>);

impl Temporary {
    fn create(dir: &Path, prefix: &OsString) -> std::io::Result<(File, Temporary)> {
        let mut builder = tempfile::Builder::new();
        builder.prefix(prefix).suffix(".tmp");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let mut live = lock(&LIVE);
        let (file, path) = builder.tempfile_in(dir)?.into_parts();
        live.push(path.to_path_buf());
        Ok((file, Temporary(Some(path))))
    }

    /// Renames the temporary to `to` (replacing a symlink there, not its target).
    fn persist(mut self, to: &Path) -> std::io::Result<()> {
        let Some(path) = self.0.take() else {
            return Ok(());
        };
        let key = path.to_path_buf();
        let mut live = lock(&LIVE);
        // On failure the returned `TempPath` is dropped here, which removes the temporary.
        let result = path.persist(to).map_err(|e| e.error);
        live.retain(|p| *p != key);
        result
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        if let Some(path) = self.0.take() {
            let key = path.to_path_buf();
            // Removed first, unlisted second: a signal in between finds nothing left to remove.
            drop(path);
            lock(&LIVE).retain(|p| *p != key);
        }
    }
}

/// Installs the handler for SIGINT, SIGTERM and SIGHUP (Ctrl-C on Windows): it removes every
/// temporary file being written and exits with [`EXIT_SIGNALLED`], or, the first time, calls the
/// action set by [`stop_on_termination`] if there is one. Call it once, before any work.
pub fn remove_temporaries_on_termination() -> Result<(), ctrlc::Error> {
    ctrlc::set_handler(|| {
        let graceful = lock(&ON_SIGNAL).take();
        match graceful {
            Some(stop) => stop(),
            None => {
                // The lock is kept until the process ends: no temporary is created or renamed
                // after these are removed.
                let live = lock(&LIVE);
                for path in live.iter() {
                    let _ = std::fs::remove_file(path);
                }
                eprintln!("stopped by a signal");
                std::process::exit(EXIT_SIGNALLED);
            }
        }
    })
}

/// Makes the next termination signal call `stop` (which should end the work soon, letting every
/// write finish or remove its temporary) instead of exiting; a signal after that still exits at
/// once, removing the temporaries.
pub fn stop_on_termination(stop: impl FnOnce() + Send + 'static) {
    *lock(&ON_SIGNAL) = Some(Box::new(stop));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir_entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_at_a_guessable_temporary_name_or_the_output_is_not_written_through() {
        let outside = tempfile::Builder::new()
            .prefix("rondo-victim-")
            .tempdir()
            .expect("temp dir");
        let dir = tempfile::Builder::new()
            .prefix("rondo-atomic-")
            .tempdir()
            .expect("temp dir");
        let victim = outside.path().join("victim");
        std::fs::write(&victim, b"precious").expect("write victim");
        // A link at the name a writer that derives its temporary from the process id would open
        // with O_TRUNC, and a link at the output itself.
        let guessed = dir
            .path()
            .join(format!(".out.txt.{}.tmp", std::process::id()));
        std::os::unix::fs::symlink(&victim, &guessed).expect("symlink");
        let out = dir.path().join("out.txt");
        std::os::unix::fs::symlink(&victim, &out).expect("symlink");
        write_bytes(&out, b"new").expect("write");
        assert_eq!(std::fs::read(&victim).expect("victim"), b"precious");
        assert_eq!(std::fs::read(&out).expect("out"), b"new");
        assert!(
            !std::fs::symlink_metadata(&out)
                .expect("out")
                .file_type()
                .is_symlink(),
            "the rename replaces the link itself"
        );
        assert_eq!(
            dir_entries(dir.path()),
            [
                format!(".out.txt.{}.tmp", std::process::id()),
                "out.txt".into()
            ]
        );
    }

    #[cfg(unix)]
    #[test]
    fn the_output_gets_the_permissions_of_a_created_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("temp dir");
        let probe = dir.path().join("probe");
        File::create(&probe).expect("probe");
        let out = dir.path().join("out.txt");
        write_bytes(&out, b"x").expect("write");
        let mode = |p: &Path| std::fs::metadata(p).expect("meta").permissions().mode();
        assert_eq!(mode(&out), mode(&probe));
    }

    #[cfg(unix)]
    #[test]
    fn a_replaced_file_keeps_its_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("temp dir");
        let out = dir.path().join("scene.ron");
        std::fs::write(&out, b"old").expect("write");
        for mode in [0o600, 0o640, 0o664] {
            std::fs::set_permissions(&out, std::fs::Permissions::from_mode(mode)).expect("chmod");
            write_bytes(&out, b"new").expect("write");
            let kept = std::fs::metadata(&out).expect("meta").permissions().mode() & 0o777;
            assert_eq!(kept, mode, "{mode:o}");
        }
    }

    #[test]
    fn a_failed_write_keeps_the_old_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().expect("temp dir");
        let out = dir.path().join("out.txt");
        std::fs::write(&out, b"old").expect("write");
        let failed = write_atomically(&out, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("encoder failed"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&out).expect("out"), b"old");
        assert_eq!(dir_entries(dir.path()), ["out.txt"]);
        assert!(write_bytes(&dir.path().join("missing/x"), b"x").is_err());
        assert!(write_bytes(Path::new("/"), b"x").is_err());
    }
}
