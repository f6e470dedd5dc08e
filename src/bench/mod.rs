//! Macro benchmarks run by `rondo bench …`: deterministic inputs, interleaved repetitions,
//! results written as CSV, a Markdown table and an SVG chart.

pub mod accuracy;
pub mod accuracy_chart;
pub mod accuracy_rows;
pub mod accuracy_summary;
pub mod chart;
pub mod environment;
pub mod instances;
pub mod layout;
pub mod layout_rows;
pub mod load;
pub mod load_watch;
pub mod load_watch_table;
pub mod load_watch_time;
pub mod lsp;
