//! Photon maps for the caustics seen through mirrors and glass (`Method::Photons`). No ECS here.
//!
//! Light tracing connects a caustic to the camera only where the camera sees it directly; a
//! caustic seen in a mirror or through a glass ball (camera → S… → D → S… → light) is left to
//! the path tracer, which finds it only when a BSDF-sampled ray from D happens to reach the
//! light through the specular surfaces: the rare, bright samples that stay in sunlit images as
//! fireflies. The same holds for a caustic lighting what the camera sees after a diffuse
//! bounce (camera → D → D′ → S… → light). Here the light paths of each sample also leave a
//! photon where they arrive after at least one specular vertex, and the camera path gathers
//! them at its first non-specular vertex D reached through specular vertices only, and at
//! every later Lambertian vertex (where the density estimate is smooth; a glossy lobe would
//! turn single photons into speckles): Σ f(ωo, ωi) Φ / (π r²) over the photons within `r` of
//! the vertex on the same surface (Jensen 1996), the path tracer dropping the same paths
//! beyond it (see [`super::super::integrator`]). The camera's first hit is light tracing's.
//! Here S is any chain vertex of the light paths: a perfect mirror or glass, or a narrow glossy
//! conductor (the sun's highlight on a gold ball, reflected onto the ground, is a caustic too).
//!
//! Each sample index has its own photons (the light paths of that sample) and its own radius,
//! `r_s = r_1 (s + 1)^((α − 1)/2)` with α = 2/3 (Knaus and Zwicker 2011, probabilistic
//! progressive photon mapping): each sample's gather is biased by its kernel, but the average
//! over `s` samples converges to the path tracer's image as the radius shrinks, and a sample's
//! estimate depends on the scene, the seed and its index alone, so images stay bit-identical on
//! any thread count and any split of the samples. `r_1 = sqrt(A K / N)` for `N` light paths per
//! sample aimed at specular targets of summed `r²` `A`: about `K` photons per gather where the
//! flux through the targets spreads evenly over their cross-sections.
//!
//! Memory: the photons of the samples a pass traces together (at most 16 or 64 MiB:
//! `LightTracing::samples_per_group`), at most one per light path (56 bytes each, one light
//! path per 8 pixels or fewer: 7 bytes per pixel per sample held at most).

use glam::Vec3;

use crate::geometry::surface::Surface;
use crate::shading::bsdf::Bsdf;

/// Photons expected in a gather where the flux through the targets spreads evenly over their
/// cross-sections, at sample 0 (see the module's notes).
pub const PHOTONS_PER_GATHER: f32 = 16.0;

/// Knaus and Zwicker's α: the share of the photons' density each sample's radius keeps.
const ALPHA: f32 = 2.0 / 3.0;

/// Cosine above which two geometric normals count as the same surface for a gather.
const SAME_SURFACE_COS: f32 = 0.9;

/// Cells per axis at which the grid's keys saturate (2^21 in each of three 21-bit fields).
const CELL_BOUND: i64 = 1 << 20;

/// Where a light path arrived after at least one perfect specular vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// The point.
    pub p: Vec3,
    /// Unit geometric normal there.
    pub n: Vec3,
    /// Direction of the light path's ray that arrived.
    pub direction: Vec3,
    /// The light path's weight (flux over its densities).
    pub beta: Vec3,
    /// Owner slot of the surface.
    pub owner: u32,
    /// Perfect specular vertices the light path passed before it.
    pub chain: u32,
}

// The module's notes give a photon's memory as 56 bytes.
const _: () = assert!(std::mem::size_of::<Photon>() == 56);

/// One sample's photons, sorted into a grid of cells `2r` wide, and the gather's radius.
#[derive(Clone, Debug)]
pub struct PhotonMap {
    photons: Vec<Photon>,
    /// Each photon's cell key, ascending (the order of `photons`).
    keys: Vec<u64>,
    radius: f32,
    /// `1 / (2r)`.
    inv_cell: f32,
    /// `1 / (N π r²)`: a photon's weight in the density estimate, for `N` light paths.
    scale: f32,
}

/// The gather radius of sample `sample` for a first radius `first` (see the module's notes).
pub fn radius(first: f32, sample: u32) -> f32 {
    first * (sample as f32 + 1.0).powf((ALPHA - 1.0) / 2.0)
}

/// The first sample's radius for `paths` light paths per sample aimed at targets of summed
/// `r²` `area` (see the module's notes).
pub fn first_radius(area: f32, paths: u64) -> f32 {
    (area * PHOTONS_PER_GATHER / paths.max(1) as f32).sqrt()
}

impl PhotonMap {
    /// The map of `photons` left by `paths` light paths, gathered within `radius`; photons at
    /// non-finite points are dropped, and so are all of them if the radius is not a positive
    /// finite number (a degenerate scene's). `O(n log n)`, the order of equal keys kept, so
    /// the map is the same for the same photons in the same order.
    pub fn new(photons: Vec<Photon>, paths: u64, radius: f32) -> Self {
        let usable = radius > 0.0 && radius.is_finite();
        let (photons, radius) = if usable {
            (photons, radius)
        } else {
            (Vec::new(), 1.0)
        };
        let inv_cell = 0.5 / radius;
        let mut keyed: Vec<(u64, Photon)> = photons
            .into_iter()
            .filter(|ph| ph.p.is_finite())
            .map(|ph| (key(cell(ph.p, inv_cell)), ph))
            .collect();
        keyed.sort_by_key(|&(k, _)| k);
        let (keys, photons) = keyed.into_iter().unzip();
        let area = std::f32::consts::PI * radius * radius;
        Self {
            photons,
            keys,
            radius,
            inv_cell,
            scale: 1.0 / (paths.max(1) as f32 * area),
        }
    }

    /// Whether the map holds no photon.
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Radiance towards the ray `bsdf` was built for, from the photons within the radius of
    /// `s.p` on the same surface (same owner, geometric normals within `SAME_SURFACE_COS`)
    /// that passed at most `max_chain` specular vertices: Σ β f / (N π r²), with f the BSDF's
    /// non-delta part ([`Bsdf::eval`]'s value over the photon's geometric cosine, as light
    /// tracing connects).
    pub fn gather(&self, s: &Surface, bsdf: &Bsdf, max_chain: u32) -> Vec3 {
        if self.photons.is_empty() || !s.p.is_finite() {
            return Vec3::ZERO;
        }
        let r2 = self.radius * self.radius;
        let lo = cell(s.p - self.radius, self.inv_cell);
        let hi = cell(s.p + self.radius, self.inv_cell);
        let mut sum = Vec3::ZERO;
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let k = key([x, y, z]);
                    let start = self.keys.partition_point(|&c| c < k);
                    let end = start + self.keys[start..].partition_point(|&c| c == k);
                    for ph in &self.photons[start..end] {
                        if ph.owner != s.owner
                            || ph.chain > max_chain
                            || (ph.p - s.p).length_squared() >= r2
                            || ph.n.dot(s.n) < SAME_SURFACE_COS
                        {
                            continue;
                        }
                        let cos_in = ph.n.dot(ph.direction).abs();
                        if cos_in <= 0.0 {
                            continue;
                        }
                        if let Some((f_cos, _)) = bsdf.eval(-ph.direction) {
                            sum += ph.beta * f_cos / cos_in;
                        }
                    }
                }
            }
        }
        sum * self.scale
    }
}

/// The cell of point `p` in a grid of cells `1 / inv_cell` wide, saturated at [`CELL_BOUND`].
fn cell(p: Vec3, inv_cell: f32) -> [i64; 3] {
    (p * inv_cell)
        .to_array()
        .map(|c| (c.floor() as i64).clamp(-CELL_BOUND, CELL_BOUND - 1))
}

/// A cell's key: its three coordinates, offset to be non-negative, in 21 bits each.
fn key(c: [i64; 3]) -> u64 {
    let field = |v: i64| (v + CELL_BOUND) as u64;
    (field(c[0]) << 42) | (field(c[1]) << 21) | field(c[2])
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::*;
    use crate::shading::material::Material;
    use crate::shading::rng::Rng;
    use crate::shading::sampler::Sampler;
    use crate::shading::texture::Texture;

    const ALBEDO: f32 = 0.6;

    fn floor_point(x: f32, z: f32, owner: u32) -> Surface {
        Surface {
            p: Vec3::new(x, 0.0, z),
            n: Vec3::Y,
            ns: Vec3::Y,
            uv: Vec2::ZERO,
            uv1: Vec2::ZERO,
            owner,
        }
    }

    /// `count` photons of weight `beta`, spread uniformly over the square |x|, |z| ≤ 1 of
    /// the floor y = 0 (owner 0), arriving at 60° from the normal.
    fn uniform_photons(count: usize, beta: f32) -> Vec<Photon> {
        let mut rng = Rng::for_sample(7, 0, 0);
        let direction = Vec3::new(3f32.sqrt() / 2.0, -0.5, 0.0);
        (0..count)
            .map(|_| {
                let u = rng.next_2d() * 2.0 - 1.0;
                Photon {
                    p: Vec3::new(u.x, 0.0, u.y),
                    n: Vec3::Y,
                    direction,
                    beta: Vec3::splat(beta),
                    owner: 0,
                    chain: 1,
                }
            })
            .collect()
    }

    #[test]
    fn an_even_flux_gathers_to_the_radiance_of_its_irradiance() {
        // Φ = count · β / N over the 2 × 2 square: irradiance Φ / 4, and a Lambertian floor
        // of albedo ρ sends ρ/π of it: independent of where (away from the edges), of the
        // photons' angle and of the radius, within the Poisson noise of the photons counted
        // (about 1 / √(count π r² / 4)).
        let (count, paths, beta) = (200_000, 50_000, 0.5);
        let map = PhotonMap::new(uniform_photons(count, beta), paths as u64, 0.1);
        let floor = Material::Diffuse {
            albedo: Texture::Constant(Vec3::splat(ALBEDO)),
        };
        let expected = ALBEDO / std::f32::consts::PI * (count as f32 * beta / paths as f32) / 4.0;
        let in_disc = count as f32 * std::f32::consts::PI * 0.01 / 4.0;
        for (x, z) in [(0.0, 0.0), (0.5, -0.3), (-0.7, 0.6)] {
            let s = floor_point(x, z, 0);
            let bsdf = floor.bsdf(
                Vec3::new(0.0, -1.0, 0.2).normalize(),
                s.n,
                s.ns,
                Vec2::ZERO,
                || None,
            );
            let l = map.gather(&s, &bsdf, 8).x;
            assert!(
                (l - expected).abs() < 4.0 * expected / in_disc.sqrt(),
                "at ({x}, {z}): {l}, expected {expected}"
            );
        }
    }

    #[test]
    fn a_gather_counts_only_its_own_surface_side_and_chain_length() {
        let map = PhotonMap::new(uniform_photons(20_000, 1.0), 1000, 0.2);
        let floor = Material::Diffuse {
            albedo: Texture::Constant(Vec3::splat(ALBEDO)),
        };
        let s = floor_point(0.0, 0.0, 0);
        let down = Vec3::new(0.0, -1.0, 0.2).normalize();
        let bsdf = floor.bsdf(down, s.n, s.ns, Vec2::ZERO, || None);
        assert!(map.gather(&s, &bsdf, 1).x > 0.0);
        // Another owner, a longer chain than the path has rays for, a surface facing
        // elsewhere, a point beyond the photons' reach: nothing.
        assert_eq!(map.gather(&floor_point(0.0, 0.0, 1), &bsdf, 1), Vec3::ZERO);
        assert_eq!(map.gather(&s, &bsdf, 0), Vec3::ZERO);
        let wall = Surface {
            n: Vec3::X,
            ns: Vec3::X,
            ..s
        };
        let wall_bsdf = floor.bsdf(-Vec3::X, wall.n, wall.ns, Vec2::ZERO, || None);
        assert_eq!(map.gather(&wall, &wall_bsdf, 1), Vec3::ZERO);
        assert_eq!(map.gather(&floor_point(1.5, 0.0, 0), &bsdf, 1), Vec3::ZERO);
        // Seen from below, the floor's upper side's photons do not shine through it.
        let under = floor.bsdf(-down, s.n, s.ns, Vec2::ZERO, || None);
        assert_eq!(map.gather(&s, &under, 1), Vec3::ZERO);
    }

    #[test]
    fn a_degenerate_radius_gathers_nothing_and_no_nan() {
        let floor = Material::Diffuse {
            albedo: Texture::Constant(Vec3::splat(ALBEDO)),
        };
        let s = floor_point(0.0, 0.0, 0);
        let bsdf = floor.bsdf(-Vec3::Y, s.n, s.ns, Vec2::ZERO, || None);
        for radius in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let map = PhotonMap::new(uniform_photons(100, 1.0), 10, radius);
            assert!(map.is_empty());
            assert_eq!(map.gather(&s, &bsdf, 8), Vec3::ZERO, "radius {radius}");
        }
    }

    #[test]
    fn the_radius_shrinks_as_knaus_and_zwicker_say() {
        // r_s² = r_1² (s + 1)^(α − 1): the squared radius of sample 63 is 64^(−1/3) = 1/4.
        let r = radius(2.0, 63);
        assert!((r * r - 1.0).abs() < 1e-5, "{r}");
        assert_eq!(radius(2.0, 0), 2.0);
        assert!((first_radius(4.0, 64) - 1.0).abs() < 1e-6);
    }
}
