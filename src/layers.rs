//! Images with layers beside the colour: the raw colour of a denoised image and the feature
//! buffers (`--aov albedo,normal`). An `.exr` holds them as one part whose channels are `R`, `G`,
//! `B` (the image shown by any viewer) and `<layer>.R`, `<layer>.G`, `<layer>.B` per layer, the
//! naming of single-part multi-layer files (Blender's, Nuke's); a `.png` holds the colour only.

use std::path::Path;
use std::str::FromStr;

use glam::Vec3;
use image::{ImageFormat, RgbImage};

use crate::film::{OutputKind, srgb8_channel};

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

/// 8-bit sRGB image of linear `pixels`, clamped to [0, 1].
pub fn srgb8_of(width: u32, height: u32, pixels: &[Vec3]) -> RgbImage {
    let data = pixels
        .iter()
        .flat_map(|p| p.to_array())
        .map(srgb8_channel)
        .collect();
    RgbImage::from_raw(width, height, data).expect("one value per pixel")
}

/// Writes `colour` (`width` × `height` linear values) and, to an `.exr`, the `layers` beside it,
/// atomically (see [`crate::output_file::write_file`]; `sync` waits for the disk).
pub fn write_layers(
    path: &Path,
    width: u32,
    height: u32,
    colour: &[Vec3],
    layers: &[Layer],
    sync: bool,
) -> std::io::Result<()> {
    let pixels = width as usize * height as usize;
    if colour.len() != pixels || layers.iter().any(|l| l.pixels.len() != pixels) {
        return Err(std::io::Error::other(format!(
            "{}: a layer's size differs from {width}x{height}",
            path.display()
        )));
    }
    let kind = OutputKind::from_path(path).ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{}: output must end in .png or .exr", path.display()),
        )
    })?;
    crate::output_file::write_file(path, sync, |out| match kind {
        OutputKind::Png => srgb8_of(width, height, colour)
            .write_to(out, ImageFormat::Png)
            .map_err(std::io::Error::other),
        OutputKind::Exr => {
            use exr::prelude::*;
            let channel = |name: String, values: &[Vec3], c: usize| {
                AnyChannel::new(
                    name.as_str(),
                    FlatSamples::F32(values.iter().map(|v| v[c]).collect()),
                )
            };
            let mut list = SmallVec::new();
            for (c, rgb) in ["R", "G", "B"].iter().enumerate() {
                list.push(channel((*rgb).to_owned(), colour, c));
                for l in layers {
                    list.push(channel(format!("{}.{rgb}", l.name), l.pixels, c));
                }
            }
            let layer = exr::image::Layer::new(
                (width as usize, height as usize),
                LayerAttributes::default(),
                Encoding::FAST_LOSSLESS,
                AnyChannels::sort(list),
            );
            Image::from_layer(layer)
                .write()
                .to_buffered(out)
                .map_err(std::io::Error::other)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
        write_layers(&exr_path, 2, 1, &colour, &layers, false).expect("written");
        let image = exr::prelude::read_all_flat_layers_from_file(&exr_path).expect("read back");
        let channels = &image.layer_data[0].channel_data.list;
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
        write_layers(&png_path, 2, 1, &colour, &layers, false).expect("written");
        let png = image::open(&png_path).expect("png").to_rgb8();
        assert_eq!(png.get_pixel(0, 0).0, [255, 188, 137]);
        assert!(write_layers(&png_path, 3, 1, &colour, &[], false).is_err());
    }
}
