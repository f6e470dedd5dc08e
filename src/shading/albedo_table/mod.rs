//! Directional albedo tables of GGX reflection, written by
//! `cargo run --release --example make_albedo_tables` (examples/make_albedo_tables.rs,
//! which says how they are computed; about 4 minutes on 2 cores): do not edit by hand.
//! Nodes are uniform in roughness (α = roughness², row 0 the mirror) and in √μ (μ the
//! cosine of the view). Read through [`super::energy`]. One file per table. No ECS here.

/// Number of roughness nodes (rows), uniform over 0 … 1.
pub const ROUGHNESS_NODES: usize = 64;

/// Number of √μ nodes (columns), uniform over 0 … 1.
pub const COS_NODES: usize = 64;

mod conductor;
mod dielectric;

pub use conductor::{CONDUCTOR, CONDUCTOR_LOST};
pub use dielectric::{DIELECTRIC, DIELECTRIC_LOST};
