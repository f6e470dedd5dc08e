//! The environment map's sampling tables against independent truth: texel frequencies against
//! the stored density times the texel's solid angle (computed here from the texel's edges), the
//! density's integral over the sphere, the texel of a direction against the `atan2` / `acos`
//! formula of the convention in `f64`, and sampled directions against the texel they were drawn
//! in.

use std::f64::consts::{PI, TAU};

use glam::{Vec2, Vec3};
use rondo::shading::rng::Rng;
use rondo::sky::EnvironmentMap;

/// A map whose texel (x, y) has radiance `f(x, y)` in every channel.
fn map(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> EnvironmentMap {
    let mut pixels = Vec::new();
    for y in 0..height {
        for x in 0..width {
            pixels.extend([f(x, y); 3]);
        }
    }
    EnvironmentMap::from_linear(width, height, &pixels).expect("valid map")
}

/// Solid angle of a texel of row `y`: `(cos θ_y − cos θ_{y+1}) · 2π / width`.
fn solid_angle(width: u32, height: u32, y: u32) -> f64 {
    let theta = |k: u32| PI * f64::from(k) / f64::from(height);
    (theta(y).cos() - theta(y + 1).cos()) * TAU / f64::from(width)
}

/// The unit direction at the centre of texel (x, y), by the module's convention.
fn centre(width: u32, height: u32, x: u32, y: u32) -> Vec3 {
    let phi = TAU * (f64::from(x) + 0.5) / f64::from(width);
    let theta = PI * (f64::from(y) + 0.5) / f64::from(height);
    Vec3::new(
        (theta.sin() * phi.sin()) as f32,
        theta.cos() as f32,
        (-theta.sin() * phi.cos()) as f32,
    )
}

/// The texel of `d` by the convention's formula in `f64` (`u = atan2(x, −z) / 2π`,
/// `v = acos(y) / π`), and the distance in radians of its φ and θ to the nearest edge.
fn reference_texel(width: u32, height: u32, d: Vec3) -> ((usize, usize), f64) {
    let (x, y, z) = (f64::from(d.x), f64::from(d.y), f64::from(d.z));
    let mut phi = x.atan2(-z);
    if phi < 0.0 {
        phi += TAU;
    }
    let theta = (x * x + z * z).sqrt().atan2(y);
    let (w, h) = (f64::from(width), f64::from(height));
    let u = phi / TAU * w;
    let v = theta / PI * h;
    let column = (u.floor() as usize).min(width as usize - 1);
    let row = (v.floor() as usize).min(height as usize - 1);
    let to_edge = |t: f64, step: f64| {
        let f = t - t.floor();
        f.min(1.0 - f) * step
    };
    let near = to_edge(u, TAU / w).min(to_edge(v, PI / h));
    ((row, column), near)
}

/// A unit direction uniform on the sphere.
fn uniform_direction(rng: &mut Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.next_f32();
    let phi = 2.0 * std::f32::consts::PI * rng.next_f32();
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), z, s * phi.sin())
}

/// 37 × 23 texels (no power of two) with a sun 5000 times the sky, a black row and a black
/// texel.
fn sunny(x: u32, y: u32) -> f32 {
    match (x, y) {
        (_, 15) => 0.0,
        (20, 3) => 0.0,
        (10, 6) => 5000.0,
        _ => 0.5 + ((x * 7 + y * 3) % 5) as f32,
    }
}

#[test]
fn sampled_texels_follow_the_stored_density_times_the_solid_angle() {
    let (w, h) = (37u32, 23u32);
    let m = map(w, h, sunny);
    // The stored density at each texel's centre, times its solid angle; checked against
    // luminance × solid angle, which the 24-bit counts approximate within 2⁻²³ per texel.
    let weight = |x: u32, y: u32| f64::from(sunny(x, y)) * solid_angle(w, h, y);
    let total: f64 = (0..h).flat_map(|y| (0..w).map(move |x| weight(x, y))).sum();
    let mut p = vec![0.0f64; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let q = f64::from(m.lookup(centre(w, h, x, y)).1) * solid_angle(w, h, y);
            let truth = weight(x, y) / total;
            assert!(
                (q - truth).abs() < 2.5e-7 + 1e-6 * truth,
                "texel ({x}, {y}): {q} vs {truth}"
            );
            p[(y * w + x) as usize] = q;
        }
    }
    let n = 400_000u32;
    let mut bins = vec![0u32; (w * h) as usize];
    let mut rng = Rng::new(21, 4);
    for _ in 0..n {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let j = Vec2::new(rng.next_f32(), rng.next_f32());
        let s = m.sample(u, j).expect("lit map");
        assert!((s.direction.length() - 1.0).abs() < 1e-5, "{}", s.direction);
        let (row, column) = m.texel_of(s.direction);
        bins[row * w as usize + column] += 1;
    }
    // Texels expected fewer than 5 times are pooled into one bin.
    let (mut chi2, mut dof) = (0.0f64, 0u32);
    let (mut pooled_expected, mut pooled_observed) = (0.0f64, 0.0f64);
    for (k, (&q, &b)) in p.iter().zip(&bins).enumerate() {
        let expected = q * f64::from(n);
        if q == 0.0 {
            assert_eq!(b, 0, "texel {k} has probability 0");
        } else if expected < 5.0 {
            pooled_expected += expected;
            pooled_observed += f64::from(b);
        } else {
            chi2 += (f64::from(b) - expected).powi(2) / expected;
            dof += 1;
        }
    }
    if pooled_expected > 0.0 {
        chi2 += (pooled_observed - pooled_expected).powi(2) / pooled_expected;
        dof += 1;
    }
    let dof = f64::from(dof - 1);
    // About the 99.99th percentile: mean + 3.7 σ of χ².
    let limit = dof + 3.7 * (2.0 * dof).sqrt();
    assert!(
        chi2 < limit,
        "χ² = {chi2:.1} with {dof} dof (limit {limit:.1})"
    );
}

#[test]
fn the_stored_density_integrates_to_one_over_the_sphere() {
    for (w, h) in [(37u32, 23u32), (64, 32), (5, 3)] {
        let m = map(w, h, sunny);
        let integral: f64 = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| f64::from(m.lookup(centre(w, h, x, y)).1) * solid_angle(w, h, y))
            .sum();
        assert!(
            (integral - 1.0).abs() < 1e-5,
            "{w}×{h}: ∫ pdf dω = {integral}"
        );
    }
}

#[test]
fn texel_of_agrees_with_atan2_and_acos_away_from_the_edges() {
    let mut rng = Rng::new(8, 9);
    for (w, h) in [
        (37u32, 23u32),
        (1024, 512),
        (7, 3),
        (2, 1),
        (1, 4),
        (2048, 1024),
    ] {
        let m = map(w, h, |x, y| (x + y) as f32);
        let (mut near_edges, mut differ) = (0u32, 0u32);
        let n = 300_000;
        for k in 0..n {
            // Uniform directions, and some of uneven length near the poles and the seam.
            let mut d = uniform_direction(&mut rng);
            match k % 4 {
                1 => d = Vec3::new(d.x * 1e-3, d.y.signum(), d.z * 1e-3) * 7.5,
                2 => d = Vec3::new(d.x * 1e-2, d.y, -d.z.abs()) * 0.3,
                _ => {}
            }
            let (truth, near) = reference_texel(w, h, d);
            if near < 1e-5 {
                near_edges += 1;
                continue;
            }
            let got = m.texel_of(d);
            if got != truth {
                differ += 1;
                eprintln!("{w}×{h}: {d} reads {got:?}, the formula {truth:?}");
            }
        }
        assert_eq!(
            differ, 0,
            "{w}×{h}: {differ} of {n} directions off their texel"
        );
        assert!(near_edges < n / 50, "{w}×{h}: {near_edges} near edges");
    }
}

#[test]
fn a_sample_lies_in_its_texel_and_carries_its_radiance_and_density() {
    // Every texel holds its own index, so a sample's radiance names the texel it was drawn
    // in; a zero row and a zero texel are never drawn.
    for (w, h) in [(37u32, 23u32), (1024, 512), (7, 3)] {
        let value = |x: u32, y: u32| {
            if y == h / 2 + 1 || (x, y) == (w / 3, h / 4) {
                0.0
            } else {
                (y * w + x + 1) as f32
            }
        };
        let m = map(w, h, value);
        let mut rng = Rng::new(u64::from(w), 3);
        let (mut on_edges, n) = (0u32, 400_000u32);
        for _ in 0..n {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let j = Vec2::new(rng.next_f32(), rng.next_f32());
            let s = m.sample(u, j).expect("lit map");
            let index = s.radiance.x as u32;
            assert!(index > 0, "a black texel was drawn");
            let drawn = (((index - 1) / w) as usize, ((index - 1) % w) as usize);
            let (row, column) = drawn;
            assert_ne!(value(column as u32, row as u32), 0.0);
            let (truth, near) = reference_texel(w, h, s.direction);
            if m.texel_of(s.direction) != drawn || truth != drawn {
                assert!(
                    near < 1e-5,
                    "{} drawn in {drawn:?} reads {truth:?}",
                    s.direction
                );
                on_edges += 1;
            } else {
                assert_eq!(m.lookup(s.direction), (s.radiance, s.pdf));
            }
        }
        // Only directions within float rounding of an edge: a handful in 400 000.
        assert!(
            on_edges <= 20,
            "{w}×{h}: {on_edges} samples read a neighbour"
        );
    }
}

#[test]
fn a_texel_of_probability_zero_is_never_drawn_on_a_grid_of_numbers() {
    let (w, h) = (37u32, 23u32);
    let m = map(w, h, sunny);
    let k = 2048;
    for a in 0..k {
        for b in 0..k {
            let u = Vec2::new((a as f32 + 0.5) / k as f32, b as f32 / k as f32);
            let s = m.sample(u, Vec2::splat(0.5)).expect("lit map");
            assert!(s.radiance.x > 0.0 && s.pdf > 0.0, "u {u} drew {s:?}");
        }
    }
}
