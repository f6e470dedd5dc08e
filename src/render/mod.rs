//! The render core: the path tracer ([`integrator`]), the passes that run it over the image in
//! parallel bands ([`pass`]), and the camera ([`camera`]). Kernels take a [`SceneView`] of plain
//! data and [`Method`], never the scene file's descriptions; the ECS converts at its boundary.
//! No ECS here.

pub mod camera;
pub mod caustics;
pub mod integrator;
pub mod medium;
pub mod pass;
pub mod pick;

use glam::Vec3;

use crate::geometry::layout::{DefaultLayout, Layout};
use crate::geometry::packed::{Geometry, Hit};
use crate::geometry::ray::Ray;
use crate::geometry::surface::Surface;
use crate::lights::LightSet;
use crate::shading::material::Material;
use crate::shading::sampler::SamplerKind;
use camera::Camera;
use caustics::photons::PhotonMap;

pub use integrator::{point_error, spawn, trace_path};
pub use pass::{render_pass, render_preview};

/// Light-transport method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// BSDF sampling only; light counts when a path hits an emitter.
    Naive,
    /// Next-event estimation: a shadow ray to a sampled point on an emitter at every diffuse
    /// vertex; emitters hit by BSDF-sampled rays after such a vertex are not counted again.
    Nee,
    /// NEE and BSDF sampling combined by the power heuristic (Veach 1997).
    #[default]
    Mis,
    /// `Mis`, with the caustic paths camera → diffuse or glossy vertex → perfect mirrors and
    /// glass → light left to light tracing ([`caustics`]): light paths from the emitters and
    /// distant lights, aimed at the specular surfaces, connected to the camera and splatted.
    Caustics,
    /// `Caustics`, with the caustics the camera sees through perfect mirrors and glass
    /// (camera → S… → D → S… → light) or after a Lambertian bounce gathered from the light
    /// paths' photons at D instead ([`caustics::photons`]), its chains S… holding narrow
    /// glossy conductors too ([`Method::chains_glossy`]): consistent, biased by each sample's
    /// gather radius.
    Photons,
}

impl Method {
    /// The method whose estimate a light-tracing-free pass (the preview) uses: `Mis` for
    /// `Caustics` and `Photons`, whose path tracer alone misses the caustic paths, itself
    /// otherwise.
    pub fn path_traced(self) -> Self {
        match self {
            Self::Caustics | Self::Photons => Self::Mis,
            m => m,
        }
    }

    /// Whether light paths are traced: `Caustics` and `Photons`.
    pub fn traces_light(self) -> bool {
        matches!(self, Self::Caustics | Self::Photons)
    }

    /// Whether the chains its light paths follow hold narrow glossy conductors besides perfect
    /// mirrors and glass ([`crate::shading::bsdf::Bsdf::is_narrow_glossy`]): `Photons`.
    pub fn chains_glossy(self) -> bool {
        self == Self::Photons
    }
}

/// Most rays a path may have, camera ray included: the sampler's dimensions are laid out for
/// paths this deep ([`EXTRA_DIMENSION`]).
pub const MAX_DEPTH: u32 = 1024;

/// Everything a render reads: a snapshot of the scene, independent of the ECS. Generic over the
/// geometry's layout, so that the whole pass is monomorphised per layout (no dispatch per ray).
#[derive(Clone, Copy)]
pub struct SceneView<'a, L: Layout = DefaultLayout> {
    /// Packed geometry and its BVHs.
    pub geometry: &'a Geometry<L>,
    /// Material table.
    pub materials: &'a [Material],
    /// Material index of every owner slot.
    pub owner_material: &'a [u32],
    /// Emitters, for next-event estimation.
    pub lights: &'a LightSet,
    /// The camera.
    pub camera: &'a Camera,
    /// Radiance of rays that leave the scene.
    pub background: Vec3,
    /// Rays per path, camera ray included.
    pub max_depth: u32,
    /// Light-transport method.
    pub method: Method,
    /// Whether paths may be ended early by Russian roulette (unbiased either way).
    pub roulette: bool,
    /// Sample generator of the converging passes.
    pub sampler: SamplerKind,
    /// Whether some material has an alpha mask ([`has_masks`] of `materials`): only then are
    /// hits tested for presence, so that scenes without masks pay nothing for them.
    pub masked: bool,
    /// Under `Method::Photons`, the photons of the sample being traced; without them the
    /// method traces as `Caustics`.
    pub photons: Option<&'a PhotonMap>,
}

impl<L: Layout> SceneView<'_, L> {
    /// The material of owner slot `owner`.
    #[inline(always)]
    pub fn material_of(&self, owner: u32) -> &Material {
        &self.materials[self.owner_material[owner as usize] as usize]
    }

    /// The local geometry at `hit` ([`Geometry::surface_reading`]), texture coordinates
    /// computed only where the material there reads them ([`Material::reads_tex_coords`]).
    #[inline(always)]
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> Surface {
        self.geometry
            .surface_reading(ray, hit, |owner| self.material_of(owner).reads_tex_coords())
    }
}

/// Whether any of `materials` has an alpha mask ([`Material::is_masked`]): the value of
/// [`SceneView::masked`].
pub fn has_masks(materials: &[Material]) -> bool {
    materials.iter().any(Material::is_masked)
}

/// Most surfaces one ray passes through where their alpha masks say they are absent (or a
/// blended surface's coverage lets it pass); the next hit then counts as present whatever its
/// mask says. A bound on the work a hostile scene (a
/// stack of thousands of masked layers) can cause, far beyond what real scenes reach.
pub const MAX_PASS_THROUGHS: u32 = 1024;

/// Counters of one render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceStats {
    /// Rays traced (camera, scattered and shadow rays).
    pub rays: u64,
    /// Samples whose radiance was NaN or infinite; they are dropped, never written.
    pub nonfinite: u64,
    /// Samples with a channel beyond the film's range (2^[`crate::film::HEADROOM_BITS`] times
    /// the scene's brightest radiance); they are clamped to it.
    pub clamped: u64,
    /// Passes traced in each layout, in the order of
    /// [`LayoutKind::ALL`](crate::geometry::layout::LayoutKind::ALL): which monomorphised
    /// code really ran.
    pub layout_passes: [u64; 4],
}

impl std::ops::Add for TraceStats {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            rays: self.rays + o.rays,
            nonfinite: self.nonfinite + o.nonfinite,
            clamped: self.clamped + o.clamped,
            layout_passes: std::array::from_fn(|k| self.layout_passes[k] + o.layout_passes[k]),
        }
    }
}

/// The render was cancelled before it finished; the film holds a partial pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cancelled;

/// The sampler's dimension layout: dimension 0 is the pixel position; bounce `b` then owns
/// dimensions `1 + b·BOUNCE_DIMENSIONS + k` with `k` one of the offsets below. Past the bounces
/// of the deepest path a scene may ask for, from [`EXTRA_DIMENSION`], come the dimensions only
/// some scenes draw ([`LENS_DIMENSION`], [`TEXEL_DIMENSION`]), so that drawing them moves no
/// dimension of the bounces.
pub const BOUNCE_DIMENSIONS: u32 = 5;
/// The choice of an emitter for next-event estimation (1D).
pub const LIGHT_CHOICE_DIMENSION: u32 = 0;
/// The point on the chosen emitter (2D).
pub const LIGHT_POINT_DIMENSION: u32 = 1;
/// The BSDF's 2D sample, then one more 1D value (glass's choice, metal's fuzz depth).
pub const BSDF_DIMENSION: u32 = 2;
/// Russian roulette (1D).
pub const ROULETTE_DIMENSION: u32 = 4;
/// The first dimension past every bounce of a path of [`MAX_DEPTH`] rays.
pub const EXTRA_DIMENSION: u32 = 1 + MAX_DEPTH * BOUNCE_DIMENSIONS;
/// The position on the lens (2D), drawn only by a camera with an aperture.
pub const LENS_DIMENSION: u32 = EXTRA_DIMENSION;
/// Bounce `b`'s position within an environment map's texel (2D) at `TEXEL_DIMENSION + b`, drawn
/// only when next-event estimation picked the map.
pub const TEXEL_DIMENSION: u32 = EXTRA_DIMENSION + 1;
/// Bounce `b`'s passes through blended surfaces ([`Material::coverage`] between 0 and 1), 1D:
/// at `TRANSPARENCY_DIMENSION + 2b` for the ray that finds the bounce's hit, `+ 2b + 1` for its
/// shadow ray. One value serves every blended surface along the ray (see `first_present`);
/// drawn only where a ray meets one.
pub const TRANSPARENCY_DIMENSION: u32 = TEXEL_DIMENSION + MAX_DEPTH;
/// Bounce `b`'s choice of the component a mix shades as ([`Material::component`]), 1D, at
/// `COMPONENT_DIMENSION + b`; drawn only where the bounce's hit is a mix.
pub const COMPONENT_DIMENSION: u32 = TRANSPARENCY_DIMENSION + 2 * MAX_DEPTH;
