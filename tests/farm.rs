//! Split renders: partials of sample ranges merge, in any order, into the single-process image
//! bit for bit; merges refuse what does not belong together; resumes continue a partial; files
//! are written atomically; the Slurm script splits as the library does.

mod common;

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::process::Command;

use rondo::farm::{Samples, prepare, task_range};
use rondo::film::{Pixel, write_atomically};
use rondo::partial::{merge, plan_merge, read_meta, write_output};
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
    let out = dir.join(name);
    let mut r = Renderer::new(Some(threads), PassPlan::Single).expect("pool");
    let part = prepare(&mut r, overrides, &cornell(), &out, &Samples::Range(range))
        .unwrap_or_else(|e| panic!("{e}"));
    r.render_to_completion();
    part.finish(&mut r).unwrap_or_else(|e| panic!("{e}"));
    out
}

fn merge_files(paths: &[PathBuf]) -> Vec<Pixel> {
    let plan = plan_merge(paths, Some(SPP)).unwrap_or_else(|e| panic!("{e}"));
    assert!(plan.missing.is_empty(), "{:?}", plan.missing);
    merge(paths, &plan).unwrap_or_else(|e| panic!("{e}"))
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
        let mut parts: Vec<PathBuf> = cuts
            .windows(2)
            .enumerate()
            .map(|(i, w)| {
                // Odd parts on one thread, even on two: the thread count must not matter either.
                render_part(
                    &dir,
                    &format!("s{k}-{i}.exr"),
                    w[0]..w[1],
                    small(),
                    1 + i % 2,
                )
            })
            .collect();
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
            write_output(&merged_exr, &plan.meta, &merged).expect("write");
            write_output(&merged_png, &plan.meta, &merged).expect("write");
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
    write_output(&ab, &plan.meta, &merge(&halves[..2], &plan).expect("merge")).expect("write");
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
    let err = |paths: &[PathBuf]| plan_merge(paths, None).expect_err("must refuse").0;

    let e = err(&[a.clone(), b.clone(), over.clone()]);
    assert!(
        e.contains("over.exr") && e.contains("6..9") && e.contains("b.exr"),
        "{e}"
    );
    let seed = render_part(
        &dir,
        "seed.exr",
        8..12,
        Overrides {
            seed: Some(9),
            ..small()
        },
        2,
    );
    let e = err(&[a.clone(), seed]);
    assert!(
        e.contains("seed.exr") && e.contains("seed 9") && e.contains("a.exr"),
        "{e}"
    );
    let size = render_part(
        &dir,
        "size.exr",
        8..12,
        Overrides {
            width: Some(21),
            ..small()
        },
        2,
    );
    let e = err(&[a.clone(), size]);
    assert!(e.contains("size.exr") && e.contains("21x15"), "{e}");
    let depth = render_part(
        &dir,
        "depth.exr",
        8..12,
        Overrides {
            max_depth: Some(2),
            ..small()
        },
        2,
    );
    let e = err(&[a.clone(), depth]);
    assert!(e.contains("depth.exr") && e.contains("hash"), "{e}");
    // Another scene file with the same settings: the contents differ, so does the hash.
    let other = dir.join("other.ron");
    let text = std::fs::read_to_string(cornell()).expect("scene");
    std::fs::write(&other, text.replace("0.65, 0.05, 0.05", "0.6, 0.05, 0.05")).expect("write");
    let out = dir.join("scene.exr");
    let mut r = Renderer::new(Some(2), PassPlan::Single).expect("pool");
    let part = prepare(&mut r, small(), &other, &out, &Samples::Range(8..12)).expect("prepare");
    r.render_to_completion();
    part.finish(&mut r).expect("finish");
    let e = err(&[a.clone(), out]);
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
    let mut r = Renderer::new(Some(2), PassPlan::Single).expect("pool");
    let e = prepare(
        &mut r,
        o,
        &cornell(),
        &dir.join("x.exr"),
        &Samples::Resume(more.clone()),
    )
    .expect_err("nothing to add")
    .to_string();
    assert!(e.contains("already holds samples up to 16"), "{e}");
    let wide = Overrides {
        width: Some(30),
        ..o
    };
    let e = prepare(&mut r, wide, &cornell(), &dir.join("x.exr"), &resume)
        .expect_err("other size")
        .to_string();
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
