//! Tests of `bench/layout/`.

use std::path::PathBuf;

use super::options::Options;
use super::scenes::{cube_side, generate};
use crate::bench::layout_rows::Kind;
use crate::ecs::components::Shape;

#[test]
fn generated_scenes_are_deterministic_and_fill_a_cube_of_constant_density() {
    let a = generate(Kind::Triangle, 500, 1);
    assert_eq!(a, generate(Kind::Triangle, 500, 1));
    assert_ne!(a, generate(Kind::Triangle, 500, 2));
    let half = 0.5 * cube_side(500) + 0.6;
    for s in &a {
        let Shape::Triangle { a, b, c } = s else {
            panic!("{s:?}")
        };
        assert!([a, b, c].iter().all(|p| p.abs().max_element() <= half));
    }
}

#[test]
fn full_sweep_counts_run_from_100_to_the_maximum_by_half_decades() {
    let o = Options::full(PathBuf::from("x"), 1_000_000, 9);
    assert_eq!(
        o.counts,
        vec![
            100, 316, 1000, 3162, 10_000, 31_623, 100_000, 316_228, 1_000_000
        ]
    );
    assert_eq!(o.reps_at(1000), 9);
    assert_eq!(o.reps_at(100_000), 7);
    assert_eq!(o.reps_at(1_000_000), 5);
}
