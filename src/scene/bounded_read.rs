//! Reading the files a scene names (the scene itself, prefabs, meshes, images, glTF files) with
//! their size bounded before anything is allocated for them.

use std::fs::{File, Metadata};
use std::io::Read;
use std::path::Path;

/// Largest file read as part of a scene: a 8192 × 4096 float RGBA map, uncompressed, is 512
/// MiB; a scene file of 10⁶ entities written one per line about 110 MB.
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// The metadata and bytes of the regular file at `path`, of at most `limit` bytes. Errors say
/// what is wrong with the file, for the caller to say which file it is.
///
/// The size is taken from the opened file, and the read stops one byte past `limit`, so a file
/// that grows between the check and the read is refused too rather than read whole. A device or
/// a pipe (`/dev/zero`, a FIFO) would be read forever, and is refused before it is read.
pub fn read_bounded(path: &Path, limit: u64) -> Result<(Metadata, Vec<u8>), String> {
    let (file, meta) = open_regular(path)?;
    let too_big = |len: u64| format!("is {len} bytes; files of at most {limit} bytes are read");
    if meta.len() > limit {
        return Err(too_big(meta.len()));
    }
    let capacity = usize::try_from(meta.len()).map_err(|_| too_big(meta.len()))?;
    let mut bytes = Vec::with_capacity(capacity);
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "grew past {limit} bytes while it was read; files of at most {limit} bytes are read"
        ));
    }
    Ok((meta, bytes))
}

/// The regular file at `path`, opened for reading, and its metadata, for readers that stream
/// it with their own bounds (an OpenEXR partial, an image decoder with allocation limits).
/// Directories, devices and pipes are refused from the opened file's type, without waiting for
/// a FIFO's writer or reading a device.
pub fn open_regular(path: &Path) -> Result<(File, Metadata), String> {
    let file = open_without_blocking(path).map_err(|e| e.to_string())?;
    let meta = file.metadata().map_err(|e| e.to_string())?;
    if meta.is_dir() {
        return Err("is a directory, not a file".into());
    }
    if !meta.is_file() {
        return Err("is not a regular file".into());
    }
    Ok((file, meta))
}

/// Opens `path` for reading without waiting for a writer: opening a FIFO would otherwise block
/// until one came, before its type could be checked on the opened file.
fn open_without_blocking(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(rustix::fs::OFlags::NONBLOCK.bits() as i32);
    }
    options.open(path)
}

/// The text of the file at `path` (a scene or a prefab), of at most [`MAX_INPUT_BYTES`] bytes of
/// UTF-8.
pub fn read_text(path: &Path) -> Result<String, String> {
    let (_, bytes) = read_bounded(path, MAX_INPUT_BYTES)?;
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("rondo-bounded-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir.join(name)
    }

    #[test]
    fn a_file_over_the_limit_is_refused_before_it_is_read() {
        let path = temp("big.ron");
        // Sparse: the size is there, the disk blocks are not.
        let file = File::create(&path).expect("create");
        file.set_len(4097).expect("set_len");
        let err = read_bounded(&path, 4096).expect_err("over the limit");
        assert!(err.contains("is 4097 bytes"), "{err}");
        let (_, bytes) = read_bounded(&path, 4097).expect("at the limit");
        assert_eq!(bytes.len(), 4097);
    }

    #[test]
    fn devices_and_directories_are_not_read() {
        let err = read_bounded(Path::new("/dev/zero"), 1 << 20).expect_err("a device");
        assert!(err.contains("not a regular file"), "{err}");
        let err = read_bounded(&std::env::temp_dir(), 1 << 20).expect_err("a directory");
        assert!(err.contains("directory"), "{err}");
    }

    #[test]
    fn a_fifo_is_refused_without_waiting_for_a_writer() {
        let path = temp("pipe.ron");
        let _ = std::fs::remove_file(&path);
        let made = std::process::Command::new("mkfifo")
            .arg(&path)
            .status()
            .expect("mkfifo");
        assert!(made.success());
        let err = read_text(&path).expect_err("a FIFO");
        assert!(err.contains("not a regular file"), "{err}");
    }

    #[test]
    fn text_that_is_not_utf8_names_the_offset() {
        let path = temp("latin1.ron");
        std::fs::write(&path, b"Scene(\xe9)").expect("write");
        let err = read_text(&path).expect_err("not UTF-8");
        assert!(err.contains("offset 6"), "{err}");
    }
}
