//! Split renders: partials of sample ranges merge, in any order, into the single-process image
//! bit for bit; merges refuse what does not belong together; resumes continue a partial; files
//! are written atomically; the Slurm script splits as the library does.

mod common;

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::process::Command;

use rondo::farm::partial::{
    PartialMeta, Sums, merge, plan_merge, read_meta, read_partial, write_output,
};
use rondo::farm::{Samples, prepare, task_range};
use rondo::film::Features;
use rondo::film::Pixel;
use rondo::output_file::write_atomically;
use rondo::scene::format::{MAX_SPP, Method};
use rondo::shading::sampler::SamplerKind;
use rondo::{Overrides, PassPlan, Renderer};

const SPP: u32 = 16;

fn cornell() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.ron")
}

fn small() -> Overrides {
    Overrides {
        width: Some(20),
        height: Some(15),
        ..Default::default()
    }
}

/// The single-process render of every sample: its sums and its decoded .exr and .png.
fn single(dir: &Path, threads: usize) -> (Vec<Pixel>, Vec<u32>, Vec<u8>) {
    let r = common::render(
        &cornell(),
        Overrides {
            spp: Some(SPP),
            ..small()
        },
        Some(threads),
    );
    let exr = dir.join(format!("single-{threads}.exr"));
    let png = dir.join(format!("single-{threads}.png"));
    r.film().write(&exr).expect("write exr");
    r.film().write(&png).expect("write png");
    (r.film().sum.clone(), decode_exr(&exr), decode_png(&png))
}

fn decode_exr(path: &Path) -> Vec<u32> {
    let img = image::open(path).expect("decode exr").into_rgb32f();
    img.into_raw().into_iter().map(f32::to_bits).collect()
}

fn decode_png(path: &Path) -> Vec<u8> {
    image::open(path)
        .expect("decode png")
        .into_rgb8()
        .into_raw()
}

/// Renders one range (with `threads` threads) into `dir/name`, as `render --samples` does.
fn render_part(
    dir: &Path,
    name: &str,
    range: Range<u32>,
    overrides: Overrides,
    threads: usize,
) -> PathBuf {
    render_part_with(dir, name, range, overrides, threads, |_| {})
}

/// As [`render_part`], with a renderer `setup` changes first (roulette off, …).
fn render_part_with(
    dir: &Path,
    name: &str,
    range: Range<u32>,
    overrides: Overrides,
    threads: usize,
    setup: impl FnOnce(&mut Renderer),
) -> PathBuf {
    let out = dir.join(name);
    let mut r = Renderer::new(Some(threads), PassPlan::Single).expect("pool");
    setup(&mut r);
    let part = prepare(&mut r, overrides, &cornell(), &out, &Samples::Range(range))
        .unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    part.finish(&mut r).unwrap_or_else(|e| panic!("{e}"));
    out
}

/// Renders the sample ranges between consecutive `cuts` into `dir/PREFIX-i.exr`, odd parts on
/// one thread and even ones on two: the thread count must not matter either.
fn render_split(dir: &Path, prefix: &str, cuts: &[u32]) -> Vec<PathBuf> {
    cuts.windows(2)
        .enumerate()
        .map(|(i, w)| {
            render_part(
                dir,
                &format!("{prefix}-{i}.exr"),
                w[0]..w[1],
                small(),
                1 + i % 2,
            )
        })
        .collect()
}

/// The merged sums of `paths` (every sample of `0..SPP` held).
fn merge_sums(paths: &[PathBuf]) -> Sums {
    let plan = plan_merge(paths, Some(SPP)).unwrap_or_else(|e| panic!("{e}"));
    assert!(plan.missing.is_empty(), "{:?}", plan.missing);
    merge(paths, &plan).unwrap_or_else(|e| panic!("{e}"))
}

/// The merged colour sums of `paths`.
fn merge_files(paths: &[PathBuf]) -> Vec<Pixel> {
    merge_sums(paths).colour
}

/// Writes `sums` as `write_output` does.
fn write_sums(path: &Path, meta: &PartialMeta, sums: &Sums) {
    write_output(path, meta, &sums.colour, sums.features.as_ref()).expect("write");
}

/// The error of a merge of `base` with `other`, which must be refused.
fn merge_refusal(base: &Path, other: PathBuf) -> String {
    plan_merge(&[base.to_path_buf(), other], None)
        .expect_err("must not merge")
        .0
}

/// Renders samples `range` with `overrides` into `dir/name`, as [`render_part`] does, and
/// returns the error of its merge with `base`, which must be refused.
fn refused_partial(
    dir: &Path,
    base: &Path,
    name: &str,
    range: Range<u32>,
    overrides: Overrides,
) -> String {
    merge_refusal(base, render_part(dir, name, range, overrides, 2))
}

/// The error of a resume of `base` with `overrides` into `out`, which must be refused before
/// anything is rendered.
fn resume_refusal(base: &Path, overrides: Overrides, out: &Path) -> String {
    let mut r = Renderer::new(Some(1), PassPlan::Single).expect("pool");
    let resume = Samples::Resume(base.to_path_buf());
    prepare(&mut r, overrides, &cornell(), out, &resume)
        .err()
        .unwrap_or_else(|| panic!("a resume of {} is refused", base.display()))
        .to_string()
}

#[test]
fn merges_equal_the_single_render_bit_for_bit_for_any_split_and_order() {
    let dir = common::temp_dir("farm-splits");
    let (sum, exr, png) = single(&dir, 2);
    let splits: [&[u32]; 4] = [
        &[0, 16],
        &[0, 1, 16],
        &[0, 5, 9, 16],
        &[0, 3, 4, 7, 8, 13, 16],
    ];
    for (k, cuts) in splits.iter().enumerate() {
        let mut parts = render_split(&dir, &format!("s{k}"), cuts);
        for order in 0..3 {
            match order {
                1 => parts.reverse(),
                2 => parts.rotate_left(1),
                _ => {}
            }
            assert_eq!(merge_files(&parts), sum, "split {cuts:?}, order {order}");
            let plan = plan_merge(&parts, None).expect("plan");
            let merged_exr = dir.join(format!("m{k}-{order}.exr"));
            let merged_png = dir.join(format!("m{k}-{order}.png"));
            let merged = merge(&parts, &plan).expect("merge");
            write_sums(&merged_exr, &plan.meta, &merged);
            write_sums(&merged_png, &plan.meta, &merged);
            assert!(
                decode_exr(&merged_exr) == exr,
                "split {cuts:?}: EXR pixels differ"
            );
            assert!(
                decode_png(&merged_png) == png,
                "split {cuts:?}: PNG pixels differ"
            );
        }
    }
    // A merged .exr is a partial again: merges compose.
    let halves = [
        render_part(&dir, "a.exr", 0..6, small(), 2),
        render_part(&dir, "b.exr", 6..11, small(), 2),
        render_part(&dir, "c.exr", 11..16, small(), 2),
    ];
    let ab = dir.join("ab.exr");
    let plan = plan_merge(&halves[..2], None).expect("plan");
    write_sums(&ab, &plan.meta, &merge(&halves[..2], &plan).expect("merge"));
    assert_eq!(read_meta(&ab).expect("meta").ranges, vec![0..11]);
    assert_eq!(merge_files(&[halves[2].clone(), ab]), sum);
    assert_eq!(single(&dir, 1).0, sum, "one thread or two");
}

#[test]
fn merges_refuse_overlaps_and_other_renders_and_report_gaps() {
    let dir = common::temp_dir("farm-errors");
    let a = render_part(&dir, "a.exr", 0..4, small(), 2);
    let b = render_part(&dir, "b.exr", 4..8, small(), 2);
    let over = render_part(&dir, "over.exr", 6..9, small(), 2);
    let late = render_part(&dir, "late.exr", 12..16, small(), 2);
    let e = plan_merge(&[a.clone(), b.clone(), over.clone()], None)
        .expect_err("must refuse")
        .0;
    assert!(
        e.contains("over.exr") && e.contains("6..9") && e.contains("b.exr"),
        "{e}"
    );
    let seed = Overrides {
        seed: Some(9),
        ..small()
    };
    let e = refused_partial(&dir, &a, "seed.exr", 8..12, seed);
    assert!(
        e.contains("seed.exr") && e.contains("seed 9") && e.contains("a.exr"),
        "{e}"
    );
    let size = Overrides {
        width: Some(21),
        ..small()
    };
    let e = refused_partial(&dir, &a, "size.exr", 8..12, size);
    assert!(e.contains("size.exr") && e.contains("21x15"), "{e}");
    let depth = Overrides {
        max_depth: Some(2),
        ..small()
    };
    let e = refused_partial(&dir, &a, "depth.exr", 8..12, depth);
    assert!(
        e.contains("depth.exr") && e.contains("max_depth 2") && e.contains("max_depth 8"),
        "{e}"
    );
    // Another scene file with the same settings: the contents differ, so does the hash.
    let other = dir.join("other.ron");
    let text = std::fs::read_to_string(cornell()).expect("scene");
    std::fs::write(&other, text.replace("0.65, 0.05, 0.05", "0.6, 0.05, 0.05")).expect("write");
    let out = dir.join("scene.exr");
    let mut r = Renderer::new(Some(2), PassPlan::Single).expect("pool");
    let part = prepare(&mut r, small(), &other, &out, &Samples::Range(8..12)).expect("prepare");
    r.render_to_completion();
    part.finish(&mut r).expect("finish");
    let e = merge_refusal(&a, out);
    assert!(e.contains("scene.exr") && e.contains("hash"), "{e}");

    let plan = plan_merge(&[late.clone(), a.clone()], Some(SPP)).expect("gaps are no error here");
    assert_eq!(plan.missing, vec![4..12]);
    let plan = plan_merge(std::slice::from_ref(&b), Some(SPP)).expect("plan");
    assert_eq!(plan.missing, vec![0..4, 8..16]);

    // The command line: gaps refused with their ranges, merged with --allow-gaps.
    let rondo = env!("CARGO_BIN_EXE_rondo");
    let merged = dir.join("gaps.png");
    let out = Command::new(rondo)
        .args(["merge", "--spp", "16", "-o"])
        .arg(&merged)
        .args([&late, &a])
        .output()
        .expect("run rondo");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("missing samples 4..12"),
        "{stderr}"
    );
    assert!(!merged.exists());
    let out = Command::new(rondo)
        .args(["merge", "--allow-gaps", "-o"])
        .arg(&merged)
        .args([&late, &a])
        .output()
        .expect("run rondo");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(merged.exists());
}

#[test]
fn a_resume_continues_with_the_next_samples() {
    let dir = common::temp_dir("farm-resume");
    let (sum, exr, _) = single(&dir, 2);
    let first = render_part(&dir, "first.exr", 0..5, small(), 2);
    let more = dir.join("more.exr");
    let mut r = Renderer::new(Some(2), PassPlan::Single).expect("pool");
    let resume = Samples::Resume(first.clone());
    let o = Overrides {
        spp: Some(SPP),
        ..small()
    };
    let part = prepare(&mut r, o, &cornell(), &more, &resume).expect("prepare");
    assert_eq!(part.ranges(), std::slice::from_ref(&(0..SPP)));
    r.render_to_completion();
    assert_eq!(
        r.film().start,
        5,
        "only the samples after the partial are rendered"
    );
    part.finish(&mut r).expect("finish");
    assert_eq!(merge_files(std::slice::from_ref(&more)), sum);
    assert!(decode_exr(&more) == exr);
    // Nothing left to add, or another resolution: refused with the reason.
    let e = resume_refusal(&more, o, &dir.join("x.exr"));
    assert!(e.contains("already holds samples up to 16"), "{e}");
    let wide = Overrides {
        width: Some(30),
        ..o
    };
    let e = resume_refusal(&first, wide, &dir.join("x.exr"));
    assert!(e.contains("first.exr") && e.contains("20x15"), "{e}");
}

#[test]
fn files_are_replaced_atomically_or_not_at_all() {
    let dir = common::temp_dir("farm-atomic");
    let path = dir.join("image.exr");
    std::fs::write(&path, b"old").expect("write");
    let failed = write_atomically(&path, |out| {
        use std::io::Write;
        out.write_all(b"half of a new fi")?;
        Err(std::io::Error::other("disk full"))
    });
    assert!(failed.is_err());
    assert_eq!(std::fs::read(&path).expect("read"), b"old");
    let part = render_part(&dir, "image.exr", 0..2, small(), 2);
    assert_eq!(read_meta(&part).expect("meta").ranges, vec![0..2]);
    let names: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names, vec!["image.exr"], "no temporary file is left behind");
}

#[test]
fn the_slurm_script_splits_as_the_library_and_merges_after_the_array() {
    let dir = common::temp_dir("farm-slurm");
    let out = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(["farm", "slurm"])
        .arg(cornell())
        .args(["--spp", "1000", "--tasks", "7", "--width", "32", "-o"])
        .arg(dir.join("final.exr"))
        .output()
        .expect("run rondo");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let script = String::from_utf8(out.stdout).expect("utf-8");
    assert!(script.starts_with("#!/bin/bash\n"));
    assert!(script.contains("#SBATCH --array=0-6\n"));
    assert!(script.contains("--dependency=\"afterok:$SLURM_ARRAY_JOB_ID\""));
    assert!(script.contains("--dependency=\"afternotok:$SLURM_ARRAY_JOB_ID\""));
    assert!(script.contains("FLAGS=(--width 32)"));
    // The script's own range function, run by bash, gives the library's ranges.
    let start = script.find("range() {").expect("range function");
    let end = start + script[start..].find('\n').expect("line");
    let mut program = format!("SPP=1000\nTASKS=7\n{}\n", &script[start..end]);
    for i in 0..7 {
        program.push_str(&format!("range {i}\n"));
    }
    let ran = Command::new("bash")
        .arg("-c")
        .arg(program)
        .output()
        .expect("bash");
    let expected: String = (0..7)
        .map(|i| {
            let r = task_range(i, 7, 1000);
            format!("{}..{}\n", r.start, r.end)
        })
        .collect();
    assert_eq!(String::from_utf8_lossy(&ran.stdout), expected);
    assert_eq!(task_range(6, 7, 1000), 857..1000);
}

/// Every setting that changes the pixels is part of a partial's identity, so partials of
/// different renders can never be summed into one image.
#[test]
fn partials_of_another_sampler_method_or_roulette_neither_merge_nor_resume() {
    let dir = common::temp_dir("farm-identity");
    let sobol = render_part(&dir, "sobol.exr", 0..4, small(), 2);
    let independent = Overrides {
        sampler: Some(SamplerKind::Independent),
        ..small()
    };
    let e = refused_partial(&dir, &sobol, "independent.exr", 4..8, independent);
    assert!(
        e.contains("independent.exr")
            && e.contains("sampler independent")
            && e.contains("sampler sobol"),
        "{e}"
    );
    let nee = Overrides {
        method: Some(Method::Nee),
        ..small()
    };
    let e = refused_partial(&dir, &sobol, "nee.exr", 4..8, nee);
    assert!(e.contains("nee.exr") && e.contains("method nee"), "{e}");
    let no_roulette = render_part_with(&dir, "no-roulette.exr", 4..8, small(), 2, |r| {
        r.set_roulette(false)
    });
    let e = merge_refusal(&sobol, no_roulette);
    assert!(
        e.contains("no-roulette.exr") && e.contains("roulette off"),
        "{e}"
    );
    // A resume with another sampler: refused before anything is rendered.
    let more = Overrides {
        spp: Some(8),
        sampler: Some(SamplerKind::Independent),
        ..small()
    };
    let e = resume_refusal(&sobol, more, &dir.join("more.exr"));
    assert!(
        e.contains("sobol.exr") && e.contains("sampler sobol") && e.contains("--sampler"),
        "{e}"
    );
    // Same settings: the partials do belong together.
    let same = render_part(&dir, "same.exr", 4..8, small(), 2);
    let plan = plan_merge(&[sobol.clone(), same], None).expect("one render's partials");
    assert_eq!(plan.meta.ranges, vec![0..8]);
    assert!(
        plan.meta.settings.contains("sampler=sobol") && plan.meta.settings.contains("roulette=on"),
        "{}",
        plan.meta.settings
    );
}

/// The film's fixed-point shift is stored, read back and must agree: sums in other units do not
/// add up.
#[test]
fn partials_in_another_fixed_point_scale_do_not_merge() {
    let dir = common::temp_dir("farm-shift");
    let a = render_part(&dir, "a.exr", 0..4, small(), 2);
    let b = render_part(&dir, "b.exr", 4..8, small(), 2);
    let (meta, sum) = read_partial(&b).expect("read b");
    let shifted = dir.join("shifted.exr");
    let moved = PartialMeta {
        shift: meta.shift - 1,
        ..meta.clone()
    };
    write_sums(&shifted, &moved, &sum);
    assert_eq!(read_meta(&shifted).expect("meta").shift, meta.shift - 1);
    let e = merge_refusal(&a, shifted);
    assert!(
        e.contains("shifted.exr") && e.contains(&(meta.shift - 1).to_string()),
        "{e}"
    );
}

/// An EXR header's attributes, each with the byte range of its value.
type Attributes = Vec<(String, Range<usize>)>;

/// The headers of an EXR file (one, or one per part of a multi-part file), and where the offset
/// tables start (after the headers' closing null byte).
fn exr_headers(bytes: &[u8]) -> (Vec<Attributes>, usize) {
    fn text(bytes: &[u8], at: &mut usize) -> String {
        let len = bytes[*at..]
            .iter()
            .position(|&b| b == 0)
            .expect("null byte");
        let s = String::from_utf8_lossy(&bytes[*at..*at + len]).into_owned();
        *at += len + 1;
        s
    }
    // The magic number and the version field (bit 12: multi-part) come first.
    let version = u32::from_le_bytes(bytes[4..8].try_into().expect("4 bytes"));
    let multipart = version & 0x1000 != 0;
    let mut at = 8;
    let mut headers = Vec::new();
    loop {
        let mut attributes = Vec::new();
        while bytes[at] != 0 {
            let name = text(bytes, &mut at);
            let _kind = text(bytes, &mut at);
            let size = i32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
            at += 4;
            let size = usize::try_from(size).expect("attribute size");
            attributes.push((name, at..at + size));
            at += size;
        }
        at += 1;
        headers.push(attributes);
        // A multi-part file's headers end with an empty one.
        if !multipart || bytes[at] == 0 {
            break;
        }
    }
    (headers, at + usize::from(multipart))
}

/// The byte range of attribute `name`'s value in a header of [`exr_headers`].
fn attribute(header: &[(String, Range<usize>)], name: &str) -> Range<usize> {
    let (_, range) = header
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no {name}"));
    range.clone()
}

/// Per part of a multi-part file, where each of its chunks starts (the offset tables).
fn chunk_offsets(bytes: &[u8]) -> Vec<Vec<usize>> {
    let (headers, mut at) = exr_headers(bytes);
    headers
        .iter()
        .map(|h| {
            let count = attribute(h, "chunkCount");
            let count = i32::from_le_bytes(bytes[count].try_into().expect("4 bytes"));
            (0..count)
                .map(|_| {
                    let o = u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
                    at += 8;
                    usize::try_from(o).expect("offset")
                })
                .collect()
        })
        .collect()
}

/// A copy of the partial `from` at `to` whose layers' data windows say `width` × `height` (and
/// whose chunk counts agree, as a reader checks).
fn with_data_window(from: &Path, to: &Path, width: i32, height: i32) {
    let mut bytes = std::fs::read(from).expect("read");
    let (headers, _) = exr_headers(&bytes);
    let int = |bytes: &[u8], at: usize| {
        i32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
    };
    for header in &headers {
        // box2i: x min, y min, x max, y max.
        let window = attribute(header, "dataWindow");
        bytes[window.start + 8..window.start + 12].copy_from_slice(&(width - 1).to_le_bytes());
        bytes[window.start + 12..window.start + 16].copy_from_slice(&(height - 1).to_le_bytes());
        // tiledesc: tile width, tile height, level mode; one chunk per tile.
        let tiles = attribute(header, "tiles");
        let (tile_w, tile_h) = (int(&bytes, tiles.start), int(&bytes, tiles.start + 4));
        let chunks = ((width + tile_w - 1) / tile_w) * ((height + tile_h - 1) / tile_h);
        let count = attribute(header, "chunkCount");
        bytes[count].copy_from_slice(&chunks.to_le_bytes());
    }
    std::fs::write(to, bytes).expect("write");
}

/// Every attribute and the size of a partial are checked against the limits
/// of a render before anything is allocated for its pixels.
#[test]
fn a_partial_is_checked_before_anything_is_allocated_for_it() {
    let dir = common::temp_dir("farm-hostile");
    let good = render_part(&dir, "good.exr", 0..4, small(), 2);
    let (meta, sum) = read_partial(&good).expect("read");
    let crafted = |name: &str, meta: PartialMeta| {
        let path = dir.join(name);
        write_sums(&path, &meta, &sum);
        path
    };
    let refused = |path: &Path, reason: &str| {
        let e = read_meta(path).expect_err("must refuse").0;
        assert!(
            e.contains(path.to_str().expect("UTF-8")) && e.contains(reason),
            "{e}"
        );
        let e = merge_refusal(&good, path.to_path_buf());
        assert!(e.contains(reason), "{e}");
    };
    // No samples at all: merged with `good`, the image would be twice as bright.
    let empty = crafted(
        "empty.exr",
        PartialMeta {
            ranges: vec![],
            ..meta.clone()
        },
    );
    refused(&empty, "at least one sample range");
    // Samples beyond the spp limit of a render.
    let beyond = crafted(
        "beyond.exr",
        PartialMeta {
            ranges: std::slice::from_ref(&(MAX_SPP..MAX_SPP + 1)).to_vec(),
            ..meta.clone()
        },
    );
    refused(&beyond, &format!("spp must be at most {MAX_SPP}"));
    let settings = crafted(
        "settings.exr",
        PartialMeta {
            settings: meta.settings.replace("max_depth=8", "max_depth=0"),
            ..meta.clone()
        },
    );
    refused(&settings, "max_depth must be >= 1");
    let scene = crafted(
        "scene.exr",
        PartialMeta {
            scene: "x".repeat(300),
            ..meta.clone()
        },
    );
    // The writer cuts a long name to the limit the reader holds it to.
    assert_eq!(read_meta(&scene).expect("meta").scene.len(), 255);
    // A data window of 65535² (206 GB of sums), and one within each side's limit but beyond
    // the pixel limit: refused from the header alone, by the command line too, with exit 1.
    let huge = dir.join("huge.exr");
    with_data_window(&good, &huge, 65535, 65535);
    refused(&huge, "width must be at most 16384");
    let wide = dir.join("wide.exr");
    with_data_window(&good, &wide, 16384, 16384);
    refused(&wide, "width × height must be at most");
    let out = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .arg("merge")
        .arg(&huge)
        .arg("-o")
        .arg(dir.join("merged.png"))
        .output()
        .expect("run rondo");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("huge.exr") && stderr.contains("65535x65535"),
        "{stderr}"
    );
    // A block that says it is the tile at (0, 0) where the one at (1, 0) belongs: the first
    // would count twice, the second not at all. (Partials are tiled, 64² per tile; the offset
    // table says where each tile starts, and a tile starts with its x and y index.)
    let two_tiles = Overrides {
        width: Some(128),
        height: Some(8),
        ..Default::default()
    };
    let tiles = render_part(&dir, "tiles.exr", 0..1, two_tiles, 2);
    let mut bytes = std::fs::read(&tiles).expect("read");
    // A chunk of a multi-part file starts with its part's index, then its tile's x and y.
    let second = chunk_offsets(&bytes)[0][1];
    assert_eq!(
        bytes[second..second + 4],
        0i32.to_le_bytes(),
        "the colour's"
    );
    assert_eq!(
        bytes[second + 4..second + 8],
        1i32.to_le_bytes(),
        "tile 1 is at x 1"
    );
    bytes[second + 4..second + 8].copy_from_slice(&0i32.to_le_bytes());
    let twice = dir.join("twice.exr");
    std::fs::write(&twice, bytes).expect("write");
    let plan = plan_merge(std::slice::from_ref(&twice), None).expect("the header is fine");
    let Err(e) = merge(std::slice::from_ref(&twice), &plan) else {
        panic!("a tile twice was merged");
    };
    let e = e.0;
    assert!(e.contains("twice.exr") && e.contains("twice"), "{e}");
}

/// A resume reads and checks the whole partial before it renders anything.
#[test]
fn a_corrupt_resume_base_is_refused_before_rendering() {
    let dir = common::temp_dir("farm-corrupt-base");
    let base = render_part(&dir, "base.exr", 0..4, small(), 2);
    let mut bytes = std::fs::read(&base).expect("read");
    bytes.truncate(bytes.len() - 64);
    let corrupt = dir.join("corrupt.exr");
    std::fs::write(&corrupt, bytes).expect("write");
    read_meta(&corrupt).expect("the header alone is fine");
    let o = Overrides {
        spp: Some(8),
        ..small()
    };
    let e = resume_refusal(&corrupt, o, &dir.join("more.exr"));
    assert!(e.contains("corrupt.exr"), "{e}");
}

/// Runs `script` with bash in `dir` with the environment `env`; returns its stdout.
fn run_script(script: &Path, dir: &Path, env: &[(&str, &str)]) -> (bool, String) {
    let out = Command::new("bash")
        .arg(script)
        .current_dir(dir)
        .envs(env.iter().copied())
        .output()
        .expect("bash");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr),
    )
}

/// `rondo farm slurm ARGS` into `dir/render.sbatch`.
fn slurm_script<A: AsRef<std::ffi::OsStr>>(
    dir: &Path,
    args: impl IntoIterator<Item = A>,
) -> PathBuf {
    let out = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(["farm", "slurm"])
        .args(args)
        .output()
        .expect("run rondo");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let path = dir.join("render.sbatch");
    std::fs::write(&path, out.stdout).expect("write script");
    path
}

/// A task of the Slurm script renders with every override given to `farm
/// slurm`: its partial is the library's for the same overrides, bit for bit.
#[test]
fn a_slurm_task_renders_with_every_override() {
    let dir = common::temp_dir("farm-slurm-flags");
    let flags = "--spp 8 --tasks 2 --width 12 --height 9 --max-depth 5 --seed 3 --method nee \
        --sampler independent --layout aos -o";
    let mut args = vec![cornell().into_os_string()];
    args.extend(flags.split_whitespace().map(Into::into));
    args.push(dir.join("final.exr").into_os_string());
    let script = slurm_script(&dir, args);
    // Task 1 (not the first, so it queues no merge) as Slurm would start it.
    let (ok, log) = run_script(
        &script,
        &dir,
        &[("SLURM_ARRAY_TASK_ID", "1"), ("SLURM_ARRAY_TASK_MIN", "0")],
    );
    assert!(ok, "{log}");
    let task = read_partial(&dir.join("final.parts/part-0001.exr")).expect("task's partial");
    let overrides = Overrides {
        width: Some(12),
        height: Some(9),
        max_depth: Some(5),
        seed: Some(3),
        method: Some(Method::Nee),
        sampler: Some(SamplerKind::Independent),
        spp: None,
    };
    let library = render_part(&dir, "library.exr", 4..8, overrides, 2);
    let library = read_partial(&library).expect("library's partial");
    assert!(
        task.0.features,
        "a farm task's partial carries the feature buffers"
    );
    assert_eq!(task.0, library.0, "metadata");
    assert!(task.1 == library.1, "sums differ");
}

/// The commands the report prints run as written when pasted into a shell,
/// whatever the paths hold (spaces, quotes, `$(…)`).
#[test]
fn the_report_prints_commands_a_shell_runs_as_written() {
    let dir = common::temp_dir("farm-report-quoting");
    let odd = dir.join("a b $(touch pwned) 'q'");
    std::fs::create_dir_all(odd.join("final.parts")).expect("mkdir");
    let scene = odd.join("scene one.ron");
    std::fs::copy(cornell(), &scene).expect("copy scene");
    let mut args = vec![scene.into_os_string()];
    args.extend(
        "--spp 4 --tasks 2 --width 8 --height 6 -o"
            .split(' ')
            .map(Into::into),
    );
    args.push(odd.join("final.exr").into_os_string());
    let script = slurm_script(&odd, args);
    let script_text = script.to_str().expect("UTF-8");
    let (ok, report) = run_script(
        &script,
        &dir,
        &[
            ("RONDO_FARM_STEP", "report"),
            ("RONDO_FARM_ARRAY", "7"),
            ("RONDO_FARM_SCRIPT", script_text),
        ],
    );
    assert!(!ok, "the report exits 1: {report}");
    let lines: Vec<&str> = report.lines().collect();
    let after = |prefix: &str| {
        let at = lines
            .iter()
            .position(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no {prefix:?} in {report}"));
        lines[at + 1].trim_start().to_string()
    };
    let rerun = after("task 1 (samples 2..4) failed");
    let ran = Command::new("sh")
        .arg("-c")
        .arg(&rerun)
        .current_dir(&dir)
        .output()
        .expect("sh");
    assert!(
        ran.status.success(),
        "{rerun}: {}",
        String::from_utf8_lossy(&ran.stderr)
    );
    let meta = read_meta(&odd.join("final.parts/part-0001.exr")).expect("the rerun's partial");
    assert_eq!(meta.ranges, std::slice::from_ref(&(2..4)));
    assert_eq!((meta.width, meta.height), (8, 6));
    assert!(!dir.join("pwned").exists(), "{rerun} ran a command");
    // The sbatch line, with sbatch standing in for a function that prints its arguments.
    let all = after("or rerun them all");
    let ran = Command::new("sh")
        .arg("-c")
        .arg(format!("sbatch() {{ printf '%s\\n' \"$@\"; }}; {all}"))
        .current_dir(&dir)
        .output()
        .expect("sh");
    assert_eq!(
        String::from_utf8_lossy(&ran.stdout),
        format!("--array=0,1\n{script_text}\n")
    );
    assert!(!dir.join("pwned").exists(), "{all} ran a command");
}

/// The full render of every sample with the feature buffers collected: its
/// colour sums and its albedo and normal sums.
fn single_with_features() -> (Vec<Pixel>, Features) {
    let mut r = Renderer::new(Some(2), PassPlan::Single).expect("pool");
    r.set_features(true);
    r.set_overrides(Overrides {
        spp: Some(SPP),
        ..small()
    });
    r.load(&cornell()).unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    let film = r.film();
    let features = film.features.clone().expect("features were collected");
    // Not a vacuous comparison: the Cornell box has albedo and normals in most pixels (all but
    // the open front's), and they differ between pixels.
    for (name, buffer) in [("albedo", &features.albedo), ("normal", &features.normal)] {
        let set = buffer.iter().filter(|p| **p != Pixel::ZERO).count();
        assert!(set * 2 > buffer.len(), "{name}: {set} pixels");
        assert!(buffer.iter().any(|p| *p != buffer[0]), "{name}");
    }
    (film.sum.clone(), features)
}

/// Every partial carries the albedo and normal sums; merged, in any split and
/// order, they equal those of one render of every sample, bit for bit, and so does a merge of
/// merges (a merged `.exr` carries them too).
#[test]
fn partials_carry_the_feature_buffers_which_merge_bit_for_bit() {
    let dir = common::temp_dir("farm-features");
    let (colour, features) = single_with_features();
    for (k, cuts) in [&[0, 16][..], &[0, 1, 16], &[0, 5, 9, 16]]
        .iter()
        .enumerate()
    {
        let mut parts = render_split(&dir, &format!("f{k}"), cuts);
        assert!(read_meta(&parts[0]).expect("meta").features);
        for _ in 0..2 {
            let merged = merge_sums(&parts);
            assert!(merged.colour == colour, "split {cuts:?}: colour");
            assert!(
                merged.features.as_ref() == Some(&features),
                "split {cuts:?}: feature buffers"
            );
            parts.reverse();
        }
    }
    let thirds = [
        render_part(&dir, "a.exr", 0..6, small(), 2),
        render_part(&dir, "b.exr", 6..11, small(), 2),
        render_part(&dir, "c.exr", 11..16, small(), 1),
    ];
    let ab = dir.join("ab.exr");
    let plan = plan_merge(&thirds[..2], None).expect("plan");
    assert!(plan.meta.features);
    write_sums(&ab, &plan.meta, &merge(&thirds[..2], &plan).expect("merge"));
    assert!(read_meta(&ab).expect("meta").features);
    let merged = merge_sums(&[thirds[2].clone(), ab]);
    assert!(merged.colour == colour && merged.features.as_ref() == Some(&features));
    // The command line's merge writes them too.
    let out = dir.join("merged.exr");
    let ran = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .arg("merge")
        .args(&thirds)
        .arg("-o")
        .arg(&out)
        .output()
        .expect("run rondo");
    assert!(
        ran.status.success(),
        "{}",
        String::from_utf8_lossy(&ran.stderr)
    );
    let (meta, sums) = read_partial(&out).expect("read");
    assert!(meta.features && sums.features.as_ref() == Some(&features));
}

/// A resume continues a partial's feature buffers, bit for bit.
#[test]
fn a_resume_continues_the_feature_buffers() {
    let dir = common::temp_dir("farm-features-resume");
    let (colour, features) = single_with_features();
    let first = render_part(&dir, "first.exr", 0..5, small(), 2);
    let more = dir.join("more.exr");
    let mut r = Renderer::new(Some(1), PassPlan::Single).expect("pool");
    let o = Overrides {
        spp: Some(SPP),
        ..small()
    };
    let part = prepare(&mut r, o, &cornell(), &more, &Samples::Resume(first)).expect("prepare");
    r.render_to_completion();
    part.finish(&mut r).expect("finish");
    let (meta, sums) = read_partial(&more).expect("read");
    assert_eq!(meta.ranges, vec![0..SPP]);
    assert!(sums.colour == colour, "colour");
    assert!(sums.features.as_ref() == Some(&features), "feature buffers");
}

/// A `rondo-partial-2` file (the format without feature buffers), made here with the
/// exr crate from the format's description: one unnamed layer of the colour's means and sum
/// words (96-bit two's complement, least significant word first), with the metadata.
fn write_v2(path: &Path, meta: &PartialMeta, sum: &[Pixel]) {
    use exr::prelude::*;
    let (w, h) = (meta.width as usize, meta.height as usize);
    let scale = 2f64.powi(-meta.shift) / meta.count() as f64;
    let words = |v: i128| [v as u32, (v >> 32) as u32, (v >> 64) as u32];
    let channels = SpecificChannels::build()
        .with_channel("R")
        .with_channel("G")
        .with_channel("B")
        .with_channel("sum.R.0")
        .with_channel("sum.R.1")
        .with_channel("sum.R.2")
        .with_channel("sum.G.0")
        .with_channel("sum.G.1")
        .with_channel("sum.G.2")
        .with_channel("sum.B.0")
        .with_channel("sum.B.1")
        .with_channel("sum.B.2")
        .with_pixel_fn(|p: Vec2<usize>| {
            let s = sum[p.y() * w + p.x()].0;
            let m = s.map(|c| (c as f64 * scale) as f32);
            let [r, g, b] = s.map(words);
            (
                m[0], m[1], m[2], r[0], r[1], r[2], g[0], g[1], g[2], b[0], b[1], b[2],
            )
        });
    let mut attributes = LayerAttributes::default();
    let ranges: Vec<String> = meta
        .ranges
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect();
    for (key, value) in [
        ("rondo.format", "rondo-partial-2".to_string()),
        ("rondo.samples", ranges.join(",")),
        ("rondo.seed", meta.seed.to_string()),
        ("rondo.hash", format!("{:016x}", meta.hash)),
        ("rondo.fraction_bits", meta.shift.to_string()),
        ("rondo.settings", meta.settings.clone()),
        ("rondo.scene", meta.scene.clone()),
    ] {
        attributes.other.insert(
            Text::from(key),
            exr::meta::attribute::AttributeValue::Text(Text::from(value.as_str())),
        );
    }
    let layer = Layer::new((w, h), attributes, Encoding::FAST_LOSSLESS, channels);
    Image::from_layer(layer)
        .write()
        .to_file(path)
        .expect("write v2");
}

/// Partials of the format without feature buffers (`rondo-partial-2`) are still read and
/// merged, so older renders stay usable (into a partial of their format); mixed with partials that carry the
/// buffers they are refused, naming both files, and so is a resume of one.
#[test]
fn partials_without_feature_buffers_still_merge_but_not_with_those_that_have_them() {
    let dir = common::temp_dir("farm-v2");
    let (sum, exr, _) = single(&dir, 2);
    let [a, b] = [("a", 0..7), ("b", 7..SPP)].map(|(name, range)| {
        let v3 = render_part(&dir, &format!("{name}3.exr"), range, small(), 2);
        let (meta, sums) = read_partial(&v3).expect("read");
        let v2 = dir.join(format!("{name}2.exr"));
        write_v2(&v2, &meta, &sums.colour);
        (v2, v3)
    });
    let meta = read_meta(&a.0).expect("a v2 partial reads");
    assert!(!meta.features);
    let merged = merge_sums(&[a.0.clone(), b.0.clone()]);
    assert!(merged.colour == sum && merged.features.is_none());
    // The command line: the merged image is a partial of their format, with the same pixels.
    let out = dir.join("merged.exr");
    let ran = Command::new(env!("CARGO_BIN_EXE_rondo"))
        .arg("merge")
        .args([&a.0, &b.0])
        .arg("-o")
        .arg(&out)
        .output()
        .expect("run rondo");
    assert!(
        ran.status.success(),
        "{}",
        String::from_utf8_lossy(&ran.stderr)
    );
    let bytes = std::fs::read(&out).expect("read");
    let (headers, _) = exr_headers(&bytes);
    assert_eq!(headers.len(), 1, "one layer");
    assert!(bytes[attribute(&headers[0], "rondo.format")].starts_with(b"rondo-partial-2"));
    let (meta, sums) = read_partial(&out).expect("read");
    assert!(!meta.features && sums.colour == sum);
    assert!(decode_exr(&out) == exr);
    // A mix of formats: refused with the reason, naming both files.
    let e = merge_refusal(&a.1, b.0.clone());
    assert!(
        e.contains("b2.exr") && e.contains("a3.exr") && e.contains("rondo-partial-2"),
        "{e}"
    );
    // A resume of one: refused with the reason before rendering.
    let o = Overrides {
        spp: Some(SPP),
        ..small()
    };
    let e = resume_refusal(&a.0, o, &dir.join("more.exr"));
    assert!(e.contains("a2.exr") && e.contains("rondo-partial-2"), "{e}");
}

/// A partial whose albedo layer is truncated or malformed is refused, naming
/// the file (and the layer, where the reader can tell), by a merge and by a resume.
#[test]
fn a_partial_with_a_broken_albedo_layer_is_refused_naming_the_file() {
    let dir = common::temp_dir("farm-broken-albedo");
    let two_tiles = Overrides {
        width: Some(128),
        height: Some(8),
        ..Default::default()
    };
    let good = render_part(&dir, "good.exr", 0..1, two_tiles, 2);
    let bytes = std::fs::read(&good).expect("read");
    let offsets = chunk_offsets(&bytes);
    assert_eq!(offsets.iter().map(Vec::len).collect::<Vec<_>>(), [2, 2, 2]);
    let (headers, _) = exr_headers(&bytes);
    let variant = |name: &str, edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = bytes.clone();
        edit(&mut b);
        let path = dir.join(name);
        std::fs::write(&path, b).expect("write");
        path
    };
    let refused = |path: &Path, reason: &str| {
        // Refused from the header by the plan, or while the sums are read by the merge.
        let paths = [path.to_path_buf()];
        let e = match plan_merge(&paths, None) {
            Err(e) => e.0,
            Ok(plan) => match merge(&paths, &plan) {
                Err(e) => e.0,
                Ok(_) => panic!("{} was merged", path.display()),
            },
        };
        assert!(
            e.contains(path.to_str().expect("UTF-8")) && e.contains(reason),
            "{e}"
        );
        let o = Overrides {
            spp: Some(2),
            ..two_tiles
        };
        let e = resume_refusal(path, o, &dir.join("more.exr"));
        assert!(
            e.contains(path.to_str().expect("UTF-8")) && e.contains(reason),
            "{e}"
        );
    };
    // Cut inside the albedo's first tile.
    let cut = offsets[1].iter().min().expect("a tile") + 30;
    let truncated = variant("truncated.exr", &|b| b.truncate(cut));
    read_meta(&truncated).expect("the header alone is fine");
    refused(&truncated, "cannot decode");
    // The albedo's second tile says it is the first: one tile twice, one missing.
    let second = offsets[1][1];
    assert_eq!(
        bytes[second..second + 4],
        1i32.to_le_bytes(),
        "the albedo's"
    );
    let twice = variant("twice.exr", &|b| {
        b[second + 4..second + 8].copy_from_slice(&0i32.to_le_bytes())
    });
    refused(&twice, "of layer albedo appears twice");
    // A sum word renamed in the albedo's channel list.
    let channels = attribute(&headers[1], "channels");
    let word = channels.start
        + bytes[channels.clone()]
            .windows(7)
            .position(|w| w == b"sum.G.2")
            .expect("sum.G.2");
    let renamed = variant("renamed.exr", &|b| b[word + 6] = b'7');
    refused(
        &renamed,
        "layer albedo: a partial has no channel \"sum.G.7\"",
    );
    // The albedo in another fixed point than the colour's.
    let bits = attribute(&headers[1], "rondo.fraction_bits");
    let shifted = variant("bits.exr", &|b| {
        let last = bits.end - 2;
        b[last] = if b[last] == b'0' { b'1' } else { b'0' };
    });
    refused(&shifted, "layer albedo: rondo.fraction_bits");
    // The second layer is not the albedo.
    let name = attribute(&headers[1], "name");
    let other = variant("name.exr", &|b| b[name.start] = b'x');
    refused(&other, "expected the layer \"albedo\"");
}

/// A partial's sums are bounded by what its samples can reach (2^62 each in fixed point): a
/// crafted file beyond it, whose sums would wrap around 96 bits into a negative sum when merged,
/// is refused by name by a merge and by a resume; at the bound itself it still reads.
#[test]
fn sums_beyond_what_the_samples_reach_are_refused_by_merge_and_resume() {
    let dir = common::temp_dir("farm-overflow");
    let a = render_part(&dir, "a.exr", 0..4, small(), 2);
    let b = render_part(&dir, "b.exr", 4..8, small(), 2);
    let (meta, sums) = read_partial(&b).expect("read b");
    let reach = 4i128 << 62;
    let crafted = |name: &str, layer: usize, value: i128| {
        let mut sums = sums.clone();
        let features = sums.features.as_mut().expect("features");
        let buffer = match layer {
            0 => &mut sums.colour,
            1 => &mut features.albedo,
            _ => &mut features.normal,
        };
        buffer[7].0[1] = value;
        let path = dir.join(name);
        write_sums(&path, &meta, &sums);
        path
    };
    // At the bound, either sign, the sums read back as written.
    for value in [reach, -reach] {
        let edge = crafted("edge.exr", 0, value);
        assert_eq!(
            read_partial(&edge).expect("at the bound").1.colour[7].0[1],
            value
        );
    }
    // The top word 0x7fffffff: two such sums added would wrap to a negative sum.
    let top = i128::from(0x7fff_ffff) << 64;
    let x = crafted("x.exr", 0, top);
    let e = merge(
        std::slice::from_ref(&x),
        &plan_merge(std::slice::from_ref(&x), None).expect("plan"),
    )
    .expect_err("beyond 4 samples")
    .0;
    assert!(
        e.contains("x.exr") && e.contains("G sum of pixel (7, 0)") && e.contains("4 samples"),
        "{e}"
    );
    for (layer, name) in [(0, "colour"), (1, "albedo"), (2, "normal")] {
        for value in [reach + 1, -reach - 1, top] {
            let file = format!("over-{name}.exr");
            let over = crafted(&file, layer, value);
            let paths = [a.clone(), over.clone()];
            let plan = plan_merge(&paths, None).expect("the metadata is a render's");
            let e = merge(&paths, &plan).expect_err("refused").0;
            assert!(
                e.contains(&file) && e.contains("beyond what 4 samples reach"),
                "{e}"
            );
            let o = Overrides {
                spp: Some(SPP),
                ..small()
            };
            let e = resume_refusal(&over, o, &dir.join("more.exr"));
            assert!(e.contains(&file) && e.contains("beyond what"), "{e}");
            assert!(!dir.join("more.exr").exists());
        }
    }
}
