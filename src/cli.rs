//! What the `rondo` binary needs besides parsing its arguments: checks that output paths can be
//! written, made before any work is done for them, the text of an error, the exit codes, and
//! printing to standard output without panicking when its reader has gone.

use std::error::Error;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Exit status of a run that failed on its input: a scene, an image, an output path.
pub const EXIT_INPUT: i32 = 1;
/// Exit status of a command line that does not parse (clap's own).
pub const EXIT_USAGE: i32 = 2;

/// Why an output path cannot be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot write here: {reason}", path.display())]
pub struct OutputError {
    /// The output path as given.
    pub path: PathBuf,
    /// Why not.
    pub reason: String,
}

/// Checks that a file can be written at `path`: it is not a directory, and its directory exists
/// and accepts new files (outputs are written to a temporary file there, then renamed). Creating
/// a file is tried for real, so the answer holds whatever grants or denies it (permission bits,
/// a read-only mount, running as root).
pub fn check_output_file(path: &Path) -> Result<(), OutputError> {
    let fail = |reason: String| OutputError {
        path: path.to_path_buf(),
        reason,
    };
    if path.is_dir() {
        return Err(fail("it is a directory".into()));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.exists() {
        return Err(fail(format!("directory {} does not exist", dir.display())));
    }
    if !dir.is_dir() {
        return Err(fail(format!("{} is not a directory", dir.display())));
    }
    probe(dir).map_err(|e| fail(format!("cannot create files in {}: {e}", dir.display())))
}

/// Checks that files can be written in the directory `dir`, creating it (and its parents) if
/// it does not exist, as the commands that write there would.
pub fn check_output_dir(dir: &Path) -> Result<(), OutputError> {
    let fail = |reason: String| OutputError {
        path: dir.to_path_buf(),
        reason,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(fail("it is not a directory".into()));
    }
    std::fs::create_dir_all(dir).map_err(|e| fail(format!("cannot create it: {e}")))?;
    probe(dir).map_err(|e| fail(format!("cannot create files in it: {e}")))
}

/// Creates and removes an empty file in `dir`, of an unpredictable name (as the temporaries of
/// [`crate::output_file`]), so that nothing planted in `dir` can make the check fail.
fn probe(dir: &Path) -> std::io::Result<()> {
    tempfile::Builder::new()
        .prefix(".rondo-write-test.")
        .tempfile_in(dir)?
        .close()
}

/// One line for an error and its causes, `outer: inner: …`, leaving out a cause whose text the
/// line already holds (errors that print their source, like "cannot read image: No such file",
/// would otherwise say it twice).
pub fn error_text(error: &(dyn Error + 'static)) -> String {
    let mut text = String::new();
    let mut next = Some(error);
    while let Some(cause) = next {
        next = cause.source();
        let cause = cause.to_string();
        if text.contains(&cause) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&cause);
    }
    text
}

/// Writes `line` and a newline to standard output. `println!` panics when the reader has gone
/// (`rondo diff a.exr b.exr | head -1`); this returns the error, which [`is_closed_pipe`]
/// recognises, so the command can stop quietly.
pub fn print_line(line: impl std::fmt::Display) -> io::Result<()> {
    writeln!(io::stdout().lock(), "{line}")
}

/// Whether `e`, or an error that caused it, is a write to a pipe whose reader has gone.
pub fn is_closed_pipe(e: &(dyn Error + 'static)) -> bool {
    let mut cause = Some(e);
    while let Some(err) = cause {
        if err
            .downcast_ref::<io::Error>()
            .is_some_and(|io| io.kind() == io::ErrorKind::BrokenPipe)
        {
            return true;
        }
        cause = err.source();
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("cannot read x.png: {0}")]
    struct Outer(#[source] std::io::Error);

    #[test]
    fn a_cause_already_in_the_message_is_not_repeated() {
        let inner = std::io::Error::other("no such file");
        let e = Outer(inner);
        assert_eq!(error_text(&e), "cannot read x.png: no such file");
        let context = anyhow::Error::new(std::io::Error::other("disk full")).context("writing a");
        assert_eq!(error_text(context.as_ref()), "writing a: disk full");
    }
}
