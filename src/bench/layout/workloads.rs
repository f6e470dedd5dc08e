//! The measured workloads, each over any layout: the leaf kernel replayed, BVH traversal, a
//! render pass, the extraction from the ECS; and the clock they are timed with.

use std::hint::black_box;
use std::ops::Range;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use cpu_time::ProcessTime;
use glam::Vec3;

use super::scenes::cube_side;
use crate::bench::layout_rows::Kind;
use crate::ecs::components::{EntityName, Shape, Transform};
use crate::film::Film;
use crate::geometry::aabb::RayQuery;
use crate::geometry::layout::{Layout, Soa};
use crate::geometry::packed::{BvhPlan, Geometry};
use crate::geometry::ray::Ray;
use crate::geometry::world::world_primitives;
use crate::lights::LightSet;
use crate::render::Method;
use crate::render::camera::Camera;
use crate::render::{SceneView, has_masks, render_pass};
use crate::shading::material::Material;
use crate::shading::sampler::SamplerKind;
use crate::shading::texture::Texture;

/// Measures the CPU time of this process (all its threads), so that time spent descheduled
/// while other jobs share the machine does not count; wall time where there is no CPU clock.
pub(super) enum Stopwatch {
    Cpu(ProcessTime),
    Wall(Instant),
}

impl Stopwatch {
    pub(super) fn start() -> Self {
        ProcessTime::try_now().map_or_else(|_| Self::Wall(Instant::now()), Self::Cpu)
    }

    pub(super) fn elapsed(&self) -> Duration {
        match self {
            Self::Cpu(t) => t.try_elapsed().unwrap_or_default(),
            Self::Wall(t) => t.elapsed(),
        }
    }
}

/// The leaf visits of real closest-hit traversals, recorded to be replayed without the
/// traversal: for each visit, the ray, the leaf's slots and the `t_max` the traversal had then.
pub(super) struct Leaves {
    kind: Kind,
    work: Vec<(RayQuery, Range<usize>, f32)>,
}

impl Leaves {
    pub(super) fn new(g: &Geometry<Soa>, kind: Kind, rays: &[Ray]) -> Self {
        let mut work = Vec::new();
        for ray in rays {
            let q = RayQuery::new(*ray);
            let mut t_max = f32::INFINITY;
            match kind {
                Kind::Sphere => g.sphere_bvh.traverse(&q, &mut t_max, |slots, t| {
                    work.push((q, slots.clone(), *t));
                    Soa::closest_sphere(&g.spheres, ray, slots, t);
                    true
                }),
                Kind::Triangle => g.triangle_bvh.traverse(&q, &mut t_max, |slots, t| {
                    work.push((q, slots.clone(), *t));
                    Soa::closest_triangle(&g.triangles, &q, slots, t);
                    true
                }),
            }
        }
        Self { kind, work }
    }

    /// Primitive tests per pass.
    pub(super) fn tests(&self) -> f64 {
        self.work.iter().map(|(_, l, _)| l.len() as f64).sum()
    }

    /// Mean primitives per leaf visited.
    pub(super) fn mean_leaf(&self) -> f64 {
        self.tests() / self.work.len().max(1) as f64
    }

    pub(super) fn run<L: Layout>(&self, g: &Geometry<L>, passes: usize) {
        let mut sum = 0usize;
        for _ in 0..passes {
            match self.kind {
                Kind::Sphere => {
                    for (q, leaf, t_max) in &self.work {
                        let mut t = *t_max;
                        let hit = L::closest_sphere(&g.spheres, &q.ray, leaf.clone(), &mut t);
                        sum += hit.unwrap_or(0);
                    }
                }
                Kind::Triangle => {
                    for (q, leaf, t_max) in &self.work {
                        let mut t = *t_max;
                        let hit = L::closest_triangle(&g.triangles, q, leaf.clone(), &mut t);
                        sum += hit.map_or(0, |h| h.0);
                    }
                }
            }
        }
        black_box(sum);
    }
}

pub(super) fn traverse<L: Layout>(g: &Geometry<L>, rays: &[Ray], passes: usize) {
    let mut hits = 0u32;
    for _ in 0..passes {
        for ray in rays {
            hits += u32::from(g.intersect(ray, f32::INFINITY).is_some());
        }
    }
    black_box(hits);
}

/// A generated scene rendered by `render_pass` (what `render_frame` calls for each pass), on a
/// one-thread pool: a diffuse material under a white sky, 4 rays per path.
pub(super) struct RenderBench {
    pool: rayon::ThreadPool,
    camera: Camera,
    materials: Vec<Material>,
    owner_material: Vec<u32>,
    lights: LightSet,
    size: u32,
}

impl RenderBench {
    pub(super) fn new(g: &Geometry<Soa>, owners: usize, size: u32) -> Self {
        let side = cube_side(owners);
        let materials = vec![Material::Diffuse {
            albedo: Texture::Constant(Vec3::splat(0.7)),
        }];
        let owner_material = vec![0; owners];
        let lights = LightSet::build(g, &materials, &owner_material);
        let pool = match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
            Ok(p) => p,
            Err(e) => panic!("one-thread pool: {e}"),
        };
        Self {
            pool,
            camera: Camera::new(
                Vec3::new(0.3, 0.4, -1.6) * side,
                Vec3::new(-0.3, -0.4, 1.6),
                Vec3::Y,
                40.0,
            ),
            materials,
            owner_material,
            lights,
            size,
        }
    }

    /// Renders `spp` samples per pixel of the scene in `geometry`: returns the time and the rays
    /// traced.
    pub(super) fn run<L: Layout>(&self, geometry: &Geometry<L>, spp: usize) -> (Duration, f64) {
        let view = SceneView {
            geometry,
            materials: &self.materials,
            owner_material: &self.owner_material,
            lights: &self.lights,
            camera: &self.camera,
            background: Vec3::ONE,
            max_depth: 4,
            method: Method::default(),
            roulette: true,
            sampler: SamplerKind::default(),
            masked: has_masks(&self.materials),
            photons: None,
        };
        let mut film = Film::new(self.size, self.size);
        let cancel = AtomicBool::new(false);
        let t = Stopwatch::start();
        let stats = self
            .pool
            .install(|| render_pass(&view, &mut film, 1, 0..spp as u32, &cancel, &|_| {}));
        let time = t.elapsed();
        (time, stats.map_or(0.0, |s| s.rays as f64))
    }
}

/// ECS components → packed geometry in layout `L`, as `rebuild_geometry` does it, with the BVHs
/// given.
pub(super) fn extract<L: Layout>(world: &mut World, plan: BvhPlan) -> Geometry<L> {
    let mut query = world.query::<(&EntityName, &Shape, &Transform)>();
    let mut sorted: Vec<_> = query.iter(world).collect();
    sorted.sort_by(|a, b| a.0.0.cmp(&b.0.0));
    let mut primitives = Vec::with_capacity(sorted.len());
    for (slot, (_, shape, transform)) in sorted.iter().enumerate() {
        for p in world_primitives(shape, transform) {
            primitives.push((slot as u32, p));
        }
    }
    Geometry::pack_with(&primitives, plan)
}
