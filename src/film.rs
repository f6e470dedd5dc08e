//! The film: per-pixel sums of radiance samples, and the image files made from them.

use std::io::{BufWriter, Write};
use std::path::Path;

use glam::{DVec3, Vec3};
use image::{ImageFormat, Rgb32FImage, RgbImage};

/// Accumulated radiance per pixel, row-major from the top-left.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Sum of the samples of each pixel (f64: thousands of samples add up without drift).
    pub sum: Vec<DVec3>,
    /// Samples per pixel accumulated so far.
    pub samples: u32,
}

/// The sRGB opto-electronic transfer function: linear in `[0, 1]` → encoded.
#[inline]
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Output file kinds, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputKind {
    /// 8-bit sRGB PNG (clamped).
    Png,
    /// Linear 32-bit float OpenEXR (unclamped).
    Exr,
}

impl OutputKind {
    /// The kind for a path's extension (`.png` or `.exr`, any case).
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(Self::Png),
            "exr" => Some(Self::Exr),
            _ => None,
        }
    }
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            sum: vec![DVec3::ZERO; width as usize * height as usize],
            samples: 0,
        }
    }

    /// The mean radiance of every pixel.
    pub fn mean(&self) -> Vec<Vec3> {
        let scale = 1.0 / f64::from(self.samples.max(1));
        self.sum.iter().map(|s| (*s * scale).as_vec3()).collect()
    }

    /// 8-bit sRGB image of the clamped mean.
    pub fn to_srgb8(&self) -> RgbImage {
        let data = self
            .mean()
            .iter()
            .flat_map(|c| c.to_array())
            .map(|c| (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
            .collect();
        RgbImage::from_raw(self.width, self.height, data).expect("film size matches its pixels")
    }

    /// Linear float image of the mean, unclamped.
    pub fn to_linear(&self) -> Rgb32FImage {
        let data = self.mean().iter().flat_map(|c| c.to_array()).collect();
        Rgb32FImage::from_raw(self.width, self.height, data).expect("film size matches its pixels")
    }

    /// Writes the image atomically: to a temporary file in the same directory, then renamed over
    /// `path`, so a viewer never sees a half-written file and a failed write leaves the old one.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        self.write_synced(path, true)
    }

    /// As [`Film::write`], but without waiting for the data to reach the disk (no fsync): for
    /// live images replaced within moments, where the fsync (5–20 ms on ext4 here) would delay
    /// the first image of an edit. Readers still never see a half-written file.
    pub fn write_live(&self, path: &Path) -> std::io::Result<()> {
        self.write_synced(path, false)
    }

    fn write_synced(&self, path: &Path, sync: bool) -> std::io::Result<()> {
        let kind = OutputKind::from_path(path).ok_or_else(|| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{}: output must end in .png or .exr", path.display()),
            )
        })?;
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
        let result = (|| {
            let mut out = BufWriter::new(std::fs::File::create(&tmp)?);
            let encoded = match kind {
                OutputKind::Png => self.to_srgb8().write_to(&mut out, ImageFormat::Png),
                OutputKind::Exr => self.to_linear().write_to(&mut out, ImageFormat::OpenExr),
            };
            encoded.map_err(std::io::Error::other)?;
            out.flush()?;
            if sync {
                out.get_ref().sync_all()?;
            }
            drop(out);
            std::fs::rename(&tmp, path)
        })();
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_encoding_matches_the_standard() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.214_04) - 0.5).abs() < 1e-4);
    }

    #[test]
    fn png_clamps_and_exr_keeps_linear_values() {
        let mut film = Film::new(2, 1);
        film.sum = vec![DVec3::new(4.0, 0.5, -1.0), DVec3::new(0.0, 2.0, 0.0)];
        film.samples = 2;
        let png = film.to_srgb8();
        // Mean (2, 0.25, −0.5) clamps to (1, 0.25, 0); 0.25 linear is 0.5371 in sRGB → 137.
        assert_eq!(png.get_pixel(0, 0).0, [255, 137, 0]);
        let exr = film.to_linear();
        assert_eq!(exr.get_pixel(0, 0).0, [2.0, 0.25, -0.5]);
    }
}
