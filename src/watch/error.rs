//! Why watching could not start.

use std::path::PathBuf;

/// Why watching could not start.
#[derive(Debug, thiserror::Error)]
pub enum WatchError {
    /// The output file has an unsupported extension.
    #[error("{0}: output must end in .png or .exr")]
    Output(PathBuf),
    /// The render thread pool could not be built.
    #[error("cannot start the render threads: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    /// The file watcher could not be created.
    #[error("cannot watch files: {0}")]
    Notify(#[from] notify::Error),
    /// The scene's directory cannot be watched.
    #[error("{path}: cannot watch: {message}")]
    Directory {
        /// The scene file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The session thread could not be started.
    #[error("cannot start the watch thread: {0}")]
    Thread(#[from] std::io::Error),
    /// The session thread panicked (a bug: please report it).
    #[error("the watch thread panicked")]
    Panicked,
}
