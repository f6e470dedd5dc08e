//! The images the viewer hands out and their encodings: the latest pass ([`Frame`]: PNG, OpenEXR
//! or raw floats, each made on first request) and the newest denoised pass ([`DenoisedImages`],
//! raw floats made when it arrives).

use std::io::Cursor;
use std::sync::OnceLock;

use glam::Vec3;

use crate::denoise::DenoisedFrame;
use crate::film::{Film, OutputKind, encode_output};

/// The first 8 bytes of `/image.f32`. Then four little-endian `u32`: width, height, reload
/// number (low 32 bits) and samples per pixel; then `width × height` pixels of three
/// little-endian `f32` (linear RGB, unclamped), rows from the top. 24 bytes of header keep the
/// floats 4-byte aligned for a `Float32Array` view.
pub const RAW_MAGIC: &[u8; 8] = b"RONDOF32";

/// The encodings of a [`Frame`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// 8-bit sRGB PNG.
    Png,
    /// Linear float OpenEXR.
    Exr,
    /// Raw linear floats (see [`RAW_MAGIC`]).
    Raw,
}

/// One image the server hands out; the encodings are made on first request.
pub struct Frame {
    reload: u64,
    film: Film,
    raw: OnceLock<Vec<u8>>,
    png: OnceLock<Result<Vec<u8>, String>>,
    exr: OnceLock<Result<Vec<u8>, String>>,
}

impl Frame {
    pub(super) fn new(reload: u64, film: Film) -> Self {
        Self {
            reload,
            film,
            raw: OnceLock::new(),
            png: OnceLock::new(),
            exr: OnceLock::new(),
        }
    }

    /// The reload whose render made it.
    pub fn reload(&self) -> u64 {
        self.reload
    }

    /// Samples per pixel in it.
    pub fn samples(&self) -> u32 {
        self.film.samples
    }

    /// The raw float encoding (see [`RAW_MAGIC`]).
    pub fn raw(&self) -> &[u8] {
        self.raw.get_or_init(|| {
            let f = &self.film;
            // As `Film::mean`, without its intermediate vector.
            let (count, fixed) = (f.count(), f.fixed());
            let means = f.sum.iter().map(|s| fixed.mean(s, count));
            encode_raw(f.width, f.height, self.reload, f.samples, means)
        })
    }

    /// The bytes of one encoding (made now if it was not yet).
    pub fn bytes(&self, encoding: Encoding) -> Result<&[u8], &str> {
        match encoding {
            Encoding::Png => self.png(),
            Encoding::Exr => self.exr(),
            Encoding::Raw => Ok(self.raw()),
        }
    }

    /// PNG: the bytes of the `.png` file the output sink writes of this film.
    pub fn png(&self) -> Result<&[u8], &str> {
        encoded(&self.png, |out| {
            encode_output(&self.film.image(), OutputKind::Png, out)
        })
    }

    /// OpenEXR: the bytes of the `.exr` file the output sink writes of this film.
    pub fn exr(&self) -> Result<&[u8], &str> {
        encoded(&self.exr, |out| {
            encode_output(&self.film.image(), OutputKind::Exr, out)
        })
    }
}

/// The raw float encoding (see [`RAW_MAGIC`]) of `pixels`, `width × height` of them.
fn encode_raw(
    width: u32,
    height: u32,
    reload: u64,
    samples: u32,
    pixels: impl ExactSizeIterator<Item = Vec3>,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(24 + pixels.len() * 12);
    out.extend_from_slice(RAW_MAGIC);
    // The reload's low 32 bits, as documented.
    for v in [width, height, reload as u32, samples] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for p in pixels {
        for v in p.to_array() {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// The images of a pass of the denoise thread (see [`Feed::denoise_sink`](super::Feed::denoise_sink)), each already in the
/// raw float encoding of [`RAW_MAGIC`]: the newest denoised pass is the only one kept.
#[derive(Debug)]
pub struct DenoisedImages {
    reload: u64,
    samples: u32,
    denoised: Vec<u8>,
    albedo: Option<Vec<u8>>,
    normal: Option<Vec<u8>>,
}

/// The images of a denoised pass the server hands out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DenoisedLayer {
    /// The denoised colour.
    Denoised,
    /// The pass's mean albedo (what guided the denoiser).
    Albedo,
    /// The pass's mean shading normal, components in [-1, 1].
    Normal,
}

impl DenoisedImages {
    /// The encodings of `frame`'s denoised colour, albedo and normal. `None` if the denoised
    /// colour does not have one value per pixel (no such frame comes from the denoise thread);
    /// an albedo or normal of the wrong size is left out.
    pub(super) fn of(frame: &DenoisedFrame) -> Option<Self> {
        let images = &frame.images;
        let (width, height) = (images.width, images.height);
        let pixels = usize::try_from(u64::from(width) * u64::from(height)).ok()?;
        let encode = |values: &[Vec3]| {
            (values.len() == pixels).then(|| {
                encode_raw(
                    width,
                    height,
                    frame.reload,
                    frame.samples,
                    values.iter().copied(),
                )
            })
        };
        Some(Self {
            reload: frame.reload,
            samples: frame.samples,
            denoised: encode(&frame.denoised)?,
            albedo: images.albedo.as_deref().and_then(encode),
            normal: images.normal.as_deref().and_then(encode),
        })
    }

    /// The reload whose render made them.
    pub fn reload(&self) -> u64 {
        self.reload
    }

    /// Samples per pixel of the pass.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The raw float encoding of one image, if the pass has it (albedo and normal exist when the
    /// film collected features).
    pub fn raw(&self, layer: DenoisedLayer) -> Option<&[u8]> {
        match layer {
            DenoisedLayer::Denoised => Some(&self.denoised),
            DenoisedLayer::Albedo => self.albedo.as_deref(),
            DenoisedLayer::Normal => self.normal.as_deref(),
        }
    }
}

/// The encoding in `cell`, made by `write` on first use.
fn encoded(
    cell: &OnceLock<Result<Vec<u8>, String>>,
    write: impl FnOnce(&mut Cursor<Vec<u8>>) -> std::io::Result<()>,
) -> Result<&[u8], &str> {
    cell.get_or_init(|| {
        let mut out = Cursor::new(Vec::new());
        write(&mut out).map_err(|e| e.to_string())?;
        Ok(out.into_inner())
    })
    .as_ref()
    .map(Vec::as_slice)
    .map_err(String::as_str)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The viewer's `/image.png` and `/image.exr` are the files the output sink writes, byte
    /// for byte (one encoder for files and the viewer).
    #[test]
    fn the_viewers_images_are_the_files_written() {
        let mut film = Film::new(3, 2);
        let fixed = film.fixed();
        for (i, p) in film.sum.iter_mut().enumerate() {
            p.add(Vec3::new(i as f32 * 0.7, 2.5, -0.25), fixed);
        }
        film.samples = 1;
        let dir = tempfile::tempdir().expect("temporary directory");
        let frame = Frame::new(0, film.clone());
        for (name, bytes) in [("x.png", frame.png()), ("x.exr", frame.exr())] {
            let path = dir.path().join(name);
            film.write(&path).expect("written");
            let file = std::fs::read(&path).expect("read back");
            assert_eq!(bytes.ok(), Some(file.as_slice()), "{name}");
        }
    }

    #[test]
    fn raw_frames_carry_size_reload_samples_and_linear_means() {
        let mut film = Film::new(2, 1);
        let fixed = film.fixed();
        film.sum[0].add(glam::Vec3::new(4.0, 0.5, -1.0), fixed);
        film.sum[1].add(glam::Vec3::new(0.0, 2.0, 0.0), fixed);
        film.samples = 2;
        let frame = Frame::new(7, film);
        let raw = frame.raw();
        assert_eq!(&raw[..8], RAW_MAGIC);
        let u = |i: usize| u32::from_le_bytes(raw[8 + 4 * i..12 + 4 * i].try_into().unwrap());
        assert_eq!([u(0), u(1), u(2), u(3)], [2, 1, 7, 2]);
        let floats: Vec<f32> = raw[24..]
            .chunks(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(floats, [2.0, 0.25, -0.5, 0.0, 1.0, 0.0]);
    }
}
