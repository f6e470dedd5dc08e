//! Writing partials (and merge results).

use std::path::Path;

use super::meta::{LAYERS, MAX_SCENE_NAME, PartialMeta, SUM_CHANNELS};
use super::ranges::format_ranges;
use crate::film::{
    Durability, EXR_ENCODING, Features, FixedPoint, NORMAL_SHIFT, OutputImage, OutputKind, Pixel,
};
use crate::output_file::write_atomically;

/// Writes a partial atomically: per layer the means (`R`, `G`, `B`, so any EXR viewer shows
/// the image) and the exact sums, and the metadata. With `features` (which `meta.features` must
/// say) it is a [`super::FORMAT`] partial of three layers, the colour first; without, a
/// [`super::FORMAT_2`] one of the colour alone.
pub fn write_partial(
    path: &Path,
    meta: &PartialMeta,
    colour: &[Pixel],
    features: Option<&Features>,
) -> std::io::Result<()> {
    use exr::prelude::*;
    let (w, h) = (meta.width as usize, meta.height as usize);
    let invalid = |what: String| {
        Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{}: {what}", path.display()),
        ))
    };
    if features.is_some() != meta.features {
        return invalid(format!(
            "feature buffers given: {}, but the metadata says {}",
            features.is_some(),
            meta.features
        ));
    }
    let buffers = std::iter::once(colour)
        .chain(
            features
                .into_iter()
                .flat_map(|f| [&f.albedo[..], &f.normal[..]]),
        )
        .collect::<Vec<_>>();
    if let Some(wrong) = buffers.iter().find(|b| b.len() != w * h) {
        return invalid(format!("{} pixels for a {w}x{h} partial", wrong.len()));
    }
    let count = meta.count();
    let text = |s: &str| AttributeValue::Text(Text::from(s));
    // The colour's attributes: the metadata.
    let mut colour_attributes = LayerAttributes::default();
    let other = &mut colour_attributes.other;
    other.insert(Text::from("rondo.format"), text(meta.format()));
    other.insert(
        Text::from("rondo.samples"),
        text(&format_ranges(&meta.ranges)),
    );
    other.insert(Text::from("rondo.seed"), text(&meta.seed.to_string()));
    other.insert(
        Text::from("rondo.hash"),
        text(&format!("{:016x}", meta.hash)),
    );
    other.insert(
        Text::from("rondo.fraction_bits"),
        text(&meta.shift.to_string()),
    );
    other.insert(Text::from("rondo.settings"), text(&meta.settings));
    let scene: String = meta
        .scene
        .chars()
        .filter(|c| c.is_ascii_graphic() || *c == ' ')
        .take(MAX_SCENE_NAME)
        .collect();
    other.insert(Text::from("rondo.scene"), text(&scene));
    // Per layer: its sums, their fixed point and its attributes. A layer of a multi-layer file
    // needs a name; a feature layer says its own fixed point.
    let albedo_shift = features.map_or(meta.albedo_shift, |f| f.albedo_shift);
    let shifts = [meta.shift, albedo_shift, NORMAL_SHIFT];
    let layers: Layers<_> = buffers
        .into_iter()
        .zip(shifts)
        .zip(LAYERS)
        .enumerate()
        .map(|(i, ((sums, shift), name))| {
            let mut attributes = if i == 0 {
                colour_attributes.clone()
            } else {
                let mut a = LayerAttributes::default();
                a.other
                    .insert(Text::from("rondo.fraction_bits"), text(&shift.to_string()));
                a
            };
            if meta.features {
                attributes.layer_name = Some(Text::from(name));
            }
            let fixed = FixedPoint::new(shift);
            let [r, g, b] = SUM_CHANNELS;
            let channels = SpecificChannels::build()
                .with_channel("R")
                .with_channel("G")
                .with_channel("B")
                .with_channel(r[0])
                .with_channel(r[1])
                .with_channel(r[2])
                .with_channel(g[0])
                .with_channel(g[1])
                .with_channel(g[2])
                .with_channel(b[0])
                .with_channel(b[1])
                .with_channel(b[2])
                .with_pixel_fn(move |p: Vec2<usize>| {
                    let s = &sums[p.y() * w + p.x()];
                    let m = fixed.mean(s, count);
                    let [r0, r1, r2] = s.words(0);
                    let [g0, g1, g2] = s.words(1);
                    let [b0, b1, b2] = s.words(2);
                    (m.x, m.y, m.z, r0, r1, r2, g0, g1, g2, b0, b1, b2)
                });
            Layer::new((w, h), attributes, EXR_ENCODING, channels)
        })
        .collect();
    let image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions((w, h))),
        layers,
    );
    write_atomically(path, |out| {
        image
            .write()
            .to_buffered(out)
            .map_err(std::io::Error::other)
    })
}

/// Writes a merge result: a partial (with the feature buffers if given) if `path` ends in
/// `.exr`, an 8-bit image of the colour if `.png`.
pub fn write_output(
    path: &Path,
    meta: &PartialMeta,
    colour: &[Pixel],
    features: Option<&Features>,
) -> std::io::Result<()> {
    match OutputKind::from_path(path) {
        Some(OutputKind::Exr) => write_partial(path, meta, colour, features),
        _ => {
            let fixed = FixedPoint::new(meta.shift);
            let image = OutputImage::of_sums(meta.width, meta.height, colour, meta.count(), fixed);
            crate::film::write_output(path, &image, Durability::Synced)
        }
    }
}
