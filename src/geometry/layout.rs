//! Storage layouts of the packed primitives, behind one interface the compiler monomorphises.
//!
//! A [`Layout`] names a sphere store, a triangle store and the leaf kernels that run over them:
//!
//! | layout       | spheres                        | triangles                         | leaf kernel |
//! |--------------|--------------------------------|-----------------------------------|-------------|
//! | [`Soa`]      | [`SphereSoa`]: `cx cy cz r`    | [`TriangleSoa`]: 9 × `Vec<f32>`   | scalar      |
//! | [`Aos`]      | [`SphereAos`]: `Vec<Sphere>`   | [`TriangleAos`]: `Vec<Triangle>`  | scalar      |
//! | [`SoaSimd`]  | [`SphereSoa`]                  | [`TriangleSoa`]                   | 4 lanes     |
//! | [`Hybrid`]   | [`SphereSoa`]                  | [`TriangleAos`]                   | 4 lanes / scalar |
//!
//! Every layout stores the same `f32` values in the same slots (BVH order), and every kernel
//! performs the same IEEE operations in the same order as the scalar reference kernels
//! ([`intersect_sphere`], [`intersect_triangle`]); so hits, and whole images, are bit-identical
//! whatever the layout. Only the memory access pattern and the instruction mix differ, which is
//! what `rondo bench layout` measures.
//!
//! Why a type parameter rather than an enum matched per ray: the layout is chosen once per
//! render pass (`render_frame` matches [`LayoutKind`] and calls the generic `render_pass`), so the
//! traversal loop, the leaf loop and the kernel inline into one function per layout, with no
//! dispatch anywhere inside. Measured on the `traverse` workload (10² to 10⁵ primitives), an
//! enum matched before every `intersect` instead was within noise of the generic path (−2 % to
//! +2 %, −4 % at worst): the branch is perfectly predicted, so the cost is not speed but a
//! match in every entry point. The generic form costs one copy of the hot code per layout, and
//! a non-default layout renders from a copy of the arrays made once per BVH build
//! ([`LayoutCache`](super::packed::LayoutCache)).

use std::fmt;
use std::ops::Range;
use std::str::FromStr;

use super::aabb::RayQuery;
use super::ray::Ray;
use super::simd;
use super::sphere::intersect_sphere;
use super::store::{
    SphereAos, SphereSoa, SphereStore, TriangleAos, TriangleSoa, TriangleStore,
    closest_sphere_scalar, closest_triangle_scalar,
};
use super::triangle::{TriangleHit, intersect_triangle};

/// The layout `Geometry` uses when none is named, and `render` uses without `--layout`: no other
/// renders faster in `rondo bench layout` (BENCHMARKS.md, "SoA against AoS on an Intel Xeon").
/// Since the BVH's leaves hold about one primitive, the 4-lane sphere test of [`SoaSimd`] and
/// [`Hybrid`] mostly runs one live lane and costs more than it saves. [`LayoutKind::default`]
/// must name the same layout.
pub type DefaultLayout = Aos;

/// Primitives stored one array per field (structure of arrays), tested one at a time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Soa;

/// Primitives stored as an array of structs, tested one at a time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Aos;

/// The [`Soa`] arrays, tested [`simd::LANES`] primitives of a leaf at a time from the field
/// arrays (portable code the optimiser vectorises; no `unsafe`, no target features).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SoaSimd;

/// Spheres as in [`SoaSimd`] (field arrays, tested 4 at a time), triangles as in [`Aos`]
/// (structs, tested one at a time). A triangle is 9 floats, so its nine SoA arrays cost about
/// nine cache lines per leaf visit where 36-byte structs cost about three; a sphere is 4 floats,
/// where the lanes won while leaves held several primitives (the default until leaves came to
/// hold about one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Hybrid;

/// A layout chosen at run time: what `--layout` parses into. Matched once per render pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LayoutKind {
    /// [`Soa`].
    Soa,
    /// [`Aos`], the default.
    #[default]
    Aos,
    /// [`SoaSimd`].
    SoaSimd,
    /// [`Hybrid`].
    Hybrid,
}

impl LayoutKind {
    /// Every layout, in the order reports list them.
    pub const ALL: [LayoutKind; 4] = [
        LayoutKind::Soa,
        LayoutKind::Aos,
        LayoutKind::SoaSimd,
        LayoutKind::Hybrid,
    ];

    /// The name `--layout` accepts and reports print.
    pub const fn name(self) -> &'static str {
        match self {
            LayoutKind::Soa => "soa",
            LayoutKind::Aos => "aos",
            LayoutKind::SoaSimd => "soa-simd",
            LayoutKind::Hybrid => "hybrid",
        }
    }
}

impl fmt::Display for LayoutKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for LayoutKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown layout {s:?} (expected soa, aos, soa-simd or hybrid)"))
    }
}

/// A storage layout with its leaf kernels. The default kernels are the scalar loops of
/// [`super::store`]; a
/// layout overrides them only to test several primitives at once ([`SoaSimd`]).
///
/// Every kernel must give exactly the answer of the scalar loop: the same slot and the same bits
/// of `t` (and barycentrics), as `tests/layout.rs` checks.
pub trait Layout: Copy + Default + fmt::Debug + Send + Sync + 'static {
    /// Sphere storage.
    type Spheres: SphereStore;
    /// Triangle storage.
    type Triangles: TriangleStore;
    /// The run-time name of this layout.
    const KIND: LayoutKind;

    /// The sphere in `slots` that `ray` hits first before `*t_max`: returns its slot and lowers
    /// `*t_max` to the hit distance.
    #[inline(always)]
    fn closest_sphere(
        spheres: &Self::Spheres,
        ray: &Ray,
        slots: Range<usize>,
        t_max: &mut f32,
    ) -> Option<usize> {
        closest_sphere_scalar(spheres, ray, slots, t_max)
    }

    /// Whether `ray` hits any sphere in `slots` before `t_max`.
    #[inline(always)]
    fn any_sphere(spheres: &Self::Spheres, ray: &Ray, slots: Range<usize>, t_max: f32) -> bool {
        // A loop, not `Iterator::any`, whose `try_fold` would stay out of line
        // (see `simd::any_sphere`).
        for (c, r) in spheres.leaf(slots) {
            if intersect_sphere(ray, c, r, t_max).is_some() {
                return true;
            }
        }
        false
    }

    /// The triangle in `slots` that the ray of `q` hits first before `*t_max`: returns its slot
    /// and hit, and lowers `*t_max` to the hit distance.
    #[inline(always)]
    fn closest_triangle(
        triangles: &Self::Triangles,
        q: &RayQuery,
        slots: Range<usize>,
        t_max: &mut f32,
    ) -> Option<(usize, TriangleHit)> {
        closest_triangle_scalar(triangles, q, slots, t_max)
    }

    /// Whether the ray of `q` hits any triangle in `slots` before `t_max`.
    #[inline(always)]
    fn any_triangle(
        triangles: &Self::Triangles,
        q: &RayQuery,
        slots: Range<usize>,
        t_max: f32,
    ) -> bool {
        for [a, b, c] in triangles.leaf(slots) {
            if intersect_triangle(q, a, b, c, t_max).is_some() {
                return true;
            }
        }
        false
    }
}

impl Layout for Soa {
    type Spheres = SphereSoa;
    type Triangles = TriangleSoa;
    const KIND: LayoutKind = LayoutKind::Soa;
}

impl Layout for Aos {
    type Spheres = SphereAos;
    type Triangles = TriangleAos;
    const KIND: LayoutKind = LayoutKind::Aos;
}

impl Layout for SoaSimd {
    type Spheres = SphereSoa;
    type Triangles = TriangleSoa;
    const KIND: LayoutKind = LayoutKind::SoaSimd;

    #[inline(always)]
    fn closest_sphere(
        spheres: &SphereSoa,
        ray: &Ray,
        slots: Range<usize>,
        t_max: &mut f32,
    ) -> Option<usize> {
        simd::closest_sphere(spheres, ray, slots, t_max)
    }

    #[inline(always)]
    fn any_sphere(spheres: &SphereSoa, ray: &Ray, slots: Range<usize>, t_max: f32) -> bool {
        simd::any_sphere(spheres, ray, slots, t_max)
    }

    #[inline(always)]
    fn closest_triangle(
        triangles: &TriangleSoa,
        q: &RayQuery,
        slots: Range<usize>,
        t_max: &mut f32,
    ) -> Option<(usize, TriangleHit)> {
        simd::closest_triangle(triangles, q, slots, t_max)
    }

    #[inline(always)]
    fn any_triangle(
        triangles: &TriangleSoa,
        q: &RayQuery,
        slots: Range<usize>,
        t_max: f32,
    ) -> bool {
        simd::any_triangle(triangles, q, slots, t_max)
    }
}

impl Layout for Hybrid {
    type Spheres = SphereSoa;
    type Triangles = TriangleAos;
    const KIND: LayoutKind = LayoutKind::Hybrid;

    #[inline(always)]
    fn closest_sphere(
        spheres: &SphereSoa,
        ray: &Ray,
        slots: Range<usize>,
        t_max: &mut f32,
    ) -> Option<usize> {
        simd::closest_sphere(spheres, ray, slots, t_max)
    }

    #[inline(always)]
    fn any_sphere(spheres: &SphereSoa, ray: &Ray, slots: Range<usize>, t_max: f32) -> bool {
        simd::any_sphere(spheres, ray, slots, t_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_layout_type_and_kind_agree() {
        assert_eq!(DefaultLayout::KIND, LayoutKind::default());
    }

    #[test]
    fn layout_names_round_trip() {
        for kind in LayoutKind::ALL {
            assert_eq!(kind.name().parse::<LayoutKind>(), Ok(kind));
        }
        assert!("soaa".parse::<LayoutKind>().is_err());
    }
}
