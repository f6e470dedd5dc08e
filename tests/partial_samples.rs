//! The `rondo.samples` attribute of a partial: ranges as rondo writes them, bounded in length,
//! anything else refused by name before the pixels are read.

mod common;

use std::path::Path;

use exr::meta::attribute::{AttributeValue, Text};
use exr::prelude::WritableImage;
use rondo::farm::partial::read_meta;
use rondo::farm::{Samples, prepare};
use rondo::{Overrides, PassPlan, Renderer};

/// A copy of the partial `from` at `to` whose `rondo.samples` is `samples`.
fn with_samples(from: &Path, to: &Path, samples: &str) {
    let mut image = exr::prelude::read_all_data_from_file(from).expect("read");
    image.layer_data[0].attributes.other.insert(
        Text::from("rondo.samples"),
        AttributeValue::Text(Text::from(samples)),
    );
    image.write().to_file(to).expect("write");
}

#[test]
fn samples_followed_by_spaces_or_beyond_any_render_are_refused() {
    let dir = common::temp_dir("partial-samples");
    let out = dir.join("good.exr");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.ron");
    let mut r = Renderer::new(Some(1), PassPlan::Single).expect("pool");
    let small = Overrides {
        width: Some(4),
        height: Some(3),
        ..Default::default()
    };
    let part = prepare(&mut r, small, &scene, &out, &Samples::Range(0..4))
        .unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    part.finish(&mut r).unwrap_or_else(|e| panic!("{e}"));

    // Rewritten as rondo writes it, the file still reads: the rewrite changes nothing else.
    let same = dir.join("same.exr");
    with_samples(&out, &same, "0..4");
    assert_eq!(read_meta(&same).expect("reads").ranges, vec![0..4]);

    let spaces = format!("0..4{}", " ".repeat(5 << 20));
    // A render writes at most one range per two samples up to 2^20, each at most 17 characters
    // (`1048575..1048576,`); leading zeros past that length would still parse as 0..4.
    let too_long = format!("{}..4", "0".repeat((1 << 19) * 17));
    for (name, samples) in [
        ("spaces", spaces),
        ("tab", "0..2,\t2..4".into()),
        ("long", too_long),
    ] {
        let path = dir.join(format!("{name}.exr"));
        with_samples(&out, &path, &samples);
        let e = read_meta(&path).expect_err("must refuse").0;
        assert!(
            e.contains(&format!("{name}.exr")) && e.contains("bad rondo.samples attribute"),
            "{name}: {e}"
        );
    }
}
