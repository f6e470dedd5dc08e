//! The denoised image of a film: its mean colour, guided by the mean albedo and normal when the
//! film collected them, handed to the [`Denoiser`]. The film's sums are only read: the denoised
//! image is a new buffer beside them.

use std::sync::atomic::AtomicBool;

use glam::Vec3;

use super::{DenoiseError, DenoiseInput, Denoiser, Quality};
use crate::film::Film;

/// The per-pixel means of a film, as the denoiser and the layered outputs take them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FilmImages {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Mean colour.
    pub colour: Vec<Vec3>,
    /// Mean albedo, if the film has features.
    pub albedo: Option<Vec<Vec3>>,
    /// Mean normal, if the film has features.
    pub normal: Option<Vec<Vec3>>,
}

impl FilmImages {
    /// The means of `film`'s sums.
    pub fn of(film: &Film) -> Self {
        let count = film.count();
        let features = film.features.as_ref();
        Self {
            width: film.width,
            height: film.height,
            colour: film.mean(),
            albedo: features.map(|f| f.albedo_mean(count)),
            normal: features.map(|f| f.normal_mean(count)),
        }
    }

    /// The colour denoised by `denoiser` at `quality`, guided by the albedo and normal if
    /// present. `cancel` stops it early ([`DenoiseError::Cancelled`]).
    pub fn denoise(
        &self,
        denoiser: &Denoiser,
        quality: Quality,
        cancel: &AtomicBool,
    ) -> Result<Vec<Vec3>, DenoiseError> {
        let colour = flat(&self.colour);
        let albedo = self.albedo.as_deref().map(flat);
        let normal = self.normal.as_deref().map(flat);
        let input = DenoiseInput {
            width: self.width,
            height: self.height,
            color: &colour,
            albedo: albedo.as_deref(),
            normal: normal.as_deref(),
        };
        let out = denoiser.denoise(&input, quality, cancel)?;
        Ok(out
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect())
    }
}

fn flat(pixels: &[Vec3]) -> Vec<f32> {
    pixels.iter().flat_map(|p| p.to_array()).collect()
}
