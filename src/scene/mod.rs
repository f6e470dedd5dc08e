//! The RON scene format and its loader. Knows nothing about rendering or the ECS world.
//!
//! ```ron
//! Scene(
//!     camera: Camera(position: (0, 1, -5), look_at: (0, 1, 0), up: (0, 1, 0), fov: 40),
//!     settings: Settings(width: 320, height: 240, spp: 16, max_depth: 8,
//!                        background: (0.5, 0.7, 1.0), seed: 0),
//!     materials: {
//!         "ground": Diffuse(albedo: Checker(scale: 10, even: Constant((0.9, 0.9, 0.9)),
//!                                                    odd: Constant((0.2, 0.2, 0.2)))),
//!         "glass": Dielectric(ior: 1.5),
//!     },
//!     entities: [
//!         Entity(name: "floor", material: "ground", shape: Plane(point: (0, 0, 0), normal: (0, 1, 0))),
//!         Entity(name: "ball", material: "glass", shape: Sphere(center: (0, 1, 0), radius: 1)),
//!     ],
//! )
//! ```
//!
//! The full format is documented in `scenes/README.md`.

pub mod assets;
pub mod bounded_read;
pub mod camera_edit;
pub mod check;
pub mod error;
pub mod format;
pub mod gltf_read;
pub mod incremental;
pub mod load;
pub mod locate;
pub mod mesh;
pub mod provenance;
