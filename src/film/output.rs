//! The output sink: every image file rondo writes (a render's, each pass of a watch, a denoised
//! image with its raw colour, the feature layers of `--aov`, a merge's) goes through
//! [`write_output`]. A `.png` holds the colour as 8-bit sRGB, clamped; an `.exr` holds it as
//! linear 32-bit floats, unclamped, with each layer beside it as channels `<layer>.R`,
//! `<layer>.G`, `<layer>.B` (the naming of single-part multi-layer files: Blender's, Nuke's) in
//! one part whose `R`, `G`, `B` any viewer shows. Files are written atomically
//! ([`crate::output_file::write_file`]).

use std::io::{Seek, Write};
use std::path::Path;
use std::str::FromStr;

use glam::Vec3;
use image::{ImageFormat, RgbImage};

use super::fixed::{FixedPoint, Pixel};

/// How every EXR rondo writes is encoded: run-length compressed 64×64 tiles (the exr crate's
/// fast lossless default), written in increasing order. The default order, "unspecified", lets
/// the tiles go out in whichever order the compression threads finish them, so the same image
/// gave different bytes from run to run on a loaded machine.
pub const EXR_ENCODING: exr::image::Encoding = exr::image::Encoding {
    line_order: exr::meta::attribute::LineOrder::Increasing,
    ..exr::image::Encoding::FAST_LOSSLESS
};
/// The sRGB opto-electronic transfer function: linear in `[0, 1]` → encoded.
#[inline]
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The 8-bit sRGB value of a linear channel, clamped to [0, 1] (what a `.png` stores).
#[inline]
pub fn srgb8_channel(c: f32) -> u8 {
    (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8
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

/// A feature buffer written as a layer of an `.exr` output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Aov {
    /// The albedo of the first non-specular hit (layer `albedo`).
    Albedo,
    /// Its shading normal, facing the camera path (layer `normal`; zero where the sky is seen).
    Normal,
}

impl Aov {
    /// The layer's name, and the name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Albedo => "albedo",
            Self::Normal => "normal",
        }
    }
}

impl FromStr for Aov {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "albedo" => Ok(Self::Albedo),
            "normal" => Ok(Self::Normal),
            _ => Err(format!("unknown AOV `{s}`: expected albedo or normal")),
        }
    }
}

/// A named layer of per-pixel values, row-major from the top-left.
#[derive(Clone, Copy, Debug)]
pub struct Layer<'a> {
    /// Channel prefix in the `.exr`.
    pub name: &'a str,
    /// One value per pixel.
    pub pixels: &'a [Vec3],
}

/// The colour of an output image.
#[derive(Clone, Copy, Debug)]
pub enum Colour<'a> {
    /// The means of exact sums, made as they are encoded (never kept as a second full-size
    /// image): `count` samples per pixel in `fixed` point.
    Sums {
        /// One sum per pixel.
        sum: &'a [Pixel],
        /// Samples per pixel.
        count: u64,
        /// The fixed point of the sums.
        fixed: FixedPoint,
    },
    /// Linear values, one per pixel (a denoised image, a merge's means).
    Linear(&'a [Vec3]),
}

impl Colour<'_> {
    fn len(&self) -> usize {
        match self {
            Self::Sums { sum, .. } => sum.len(),
            Self::Linear(pixels) => pixels.len(),
        }
    }

    /// The linear value of pixel `i`.
    fn at(&self, i: usize) -> Vec3 {
        match self {
            Self::Sums { sum, count, fixed } => fixed.mean(&sum[i], *count),
            Self::Linear(pixels) => pixels[i],
        }
    }
}

/// What an output file holds: a `width` × `height` colour and, in an `.exr`, layers beside it.
#[derive(Clone, Copy, Debug)]
pub struct OutputImage<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The colour.
    pub colour: Colour<'a>,
    /// Layers written beside the colour in an `.exr` (a `.png` holds the colour only).
    pub layers: &'a [Layer<'a>],
}

impl<'a> OutputImage<'a> {
    /// The means of exact sums, no layers.
    pub fn of_sums(
        width: u32,
        height: u32,
        sum: &'a [Pixel],
        count: u64,
        fixed: FixedPoint,
    ) -> Self {
        Self {
            width,
            height,
            colour: Colour::Sums { sum, count, fixed },
            layers: &[],
        }
    }

    /// Linear `colour` with `layers` beside it.
    pub fn of_linear(width: u32, height: u32, colour: &'a [Vec3], layers: &'a [Layer<'a>]) -> Self {
        Self {
            width,
            height,
            colour: Colour::Linear(colour),
            layers,
        }
    }

    /// 8-bit sRGB image of the colour, clamped to [0, 1] (what a `.png` stores).
    pub fn srgb8(&self) -> RgbImage {
        let data = (0..self.colour.len())
            .flat_map(|i| self.colour.at(i).to_array())
            .map(srgb8_channel)
            .collect();
        RgbImage::from_raw(self.width, self.height, data).expect("one value per pixel")
    }
}

/// Whether a write waits for the data to reach the disk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Durability {
    /// It does (fsync): a finished render, a merge.
    Synced,
    /// It does not: live images replaced within moments (each pass of a watch), where the fsync
    /// (5–20 ms on ext4) would delay the first image of an edit. Readers still never see a
    /// half-written file.
    Live,
}

/// Writes `image` to `path`, a `.png` or an `.exr` by its extension, atomically.
pub fn write_output(
    path: &Path,
    image: &OutputImage,
    durability: Durability,
) -> std::io::Result<()> {
    let kind = OutputKind::from_path(path).ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{}: output must end in .png or .exr", path.display()),
        )
    })?;
    let sync = durability == Durability::Synced;
    crate::output_file::write_file(path, sync, |out| encode_output(image, kind, out))
}

/// Encodes `image` as `kind` into `out`: the bytes of the file [`write_output`] writes (and of
/// the live viewer's `/image.png` and `/image.exr`).
pub fn encode_output<W: Write + Seek>(
    image: &OutputImage,
    kind: OutputKind,
    out: &mut W,
) -> std::io::Result<()> {
    let (width, height) = (image.width, image.height);
    let pixels = width as usize * height as usize;
    if image.colour.len() != pixels || image.layers.iter().any(|l| l.pixels.len() != pixels) {
        return Err(std::io::Error::other(format!(
            "a layer's size differs from {width}x{height}"
        )));
    }
    match kind {
        OutputKind::Png => image
            .srgb8()
            .write_to(out, ImageFormat::Png)
            .map_err(std::io::Error::other),
        OutputKind::Exr if image.layers.is_empty() => {
            use exr::prelude::*;
            let w = width as usize;
            let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
                let m = image.colour.at(p.y() * w + p.x());
                (m.x, m.y, m.z)
            });
            let layer = exr::image::Layer::new(
                (w, height as usize),
                LayerAttributes::default(),
                EXR_ENCODING,
                channels,
            );
            Image::from_layer(layer)
                .write()
                .to_buffered(out)
                .map_err(std::io::Error::other)
        }
        OutputKind::Exr => {
            use exr::prelude::*;
            let channel = |name: String, value: &dyn Fn(usize) -> Vec3, c: usize| {
                AnyChannel::new(
                    name.as_str(),
                    FlatSamples::F32((0..pixels).map(|i| value(i)[c]).collect()),
                )
            };
            let colour = |i: usize| image.colour.at(i);
            let mut list = SmallVec::new();
            for (c, rgb) in ["R", "G", "B"].iter().enumerate() {
                list.push(channel((*rgb).to_owned(), &colour, c));
                for l in image.layers {
                    list.push(channel(format!("{}.{rgb}", l.name), &|i| l.pixels[i], c));
                }
            }
            let layer = exr::image::Layer::new(
                (width as usize, height as usize),
                LayerAttributes::default(),
                EXR_ENCODING,
                AnyChannels::sort(list),
            );
            Image::from_layer(layer)
                .write()
                .to_buffered(out)
                .map_err(std::io::Error::other)
        }
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
    fn aov_names_parse_and_print() {
        for a in [Aov::Albedo, Aov::Normal] {
            assert_eq!(a.name().parse::<Aov>(), Ok(a));
        }
        assert!("depth".parse::<Aov>().is_err());
    }

    #[test]
    fn an_exr_holds_every_layer_and_a_png_the_colour() {
        let dir = tempfile::tempdir().expect("temporary directory");
        let colour = [Vec3::new(2.0, 0.5, 0.25), Vec3::ZERO];
        let albedo = [Vec3::new(0.1, 0.2, 0.3), Vec3::ONE];
        let exr_path = dir.path().join("x.exr");
        let layers = [Layer {
            name: "albedo",
            pixels: &albedo,
        }];
        let image = OutputImage::of_linear(2, 1, &colour, &layers);
        write_output(&exr_path, &image, Durability::Live).expect("written");
        let read = exr::prelude::read_all_flat_layers_from_file(&exr_path).expect("read back");
        let channels = &read.layer_data[0].channel_data.list;
        let value = |name: &str, i: usize| {
            let c = channels
                .iter()
                .find(|c| c.name.to_string() == name)
                .expect(name);
            c.sample_data.value_by_flat_index(i).to_f32()
        };
        assert_eq!(value("R", 0), 2.0);
        assert_eq!(value("B", 0), 0.25);
        assert_eq!(value("albedo.G", 0), 0.2);
        assert_eq!(value("albedo.R", 1), 1.0);
        assert_eq!(channels.len(), 6);
        // The `image` crate (and so `rondo diff`) reads the colour.
        let back = image::open(&exr_path).expect("image reads it").to_rgb32f();
        assert_eq!(back.get_pixel(0, 0).0, [2.0, 0.5, 0.25]);
        let png_path = dir.path().join("x.png");
        write_output(&png_path, &image, Durability::Live).expect("written");
        let png = image::open(&png_path).expect("png").to_rgb8();
        assert_eq!(png.get_pixel(0, 0).0, [255, 188, 137]);
        let wrong = OutputImage::of_linear(3, 1, &colour, &[]);
        assert!(write_output(&png_path, &wrong, Durability::Live).is_err());
    }
}
