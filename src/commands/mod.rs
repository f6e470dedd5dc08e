//! The bodies of the `rondo` commands; `main.rs` holds only the argument types and the dispatch.

pub mod args;
pub mod bench;
pub mod bench_command;
pub mod check;
pub mod diff;
pub mod export;
pub mod farm;
pub mod merge;
pub mod render;
pub mod watch;
