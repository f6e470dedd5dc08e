//! `rondo diff` and `rondo bench accuracy`, through the real binary: exact figures on images
//! built by hand, clear errors on bad input, and a smoke run of the benchmark (nothing here
//! measures or asserts time).

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{exr_channels, scenes_dir, temp_dir};
use image::Rgb32FImage;
use rondo::metrics::{Image, REL_EPSILON, compare, lamp_out_rmse};

fn rondo(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rondo"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run rondo")
}

fn write_exr(dir: &Path, name: &str, width: u32, height: u32, data: Vec<f32>) -> PathBuf {
    let path = dir.join(name);
    Rgb32FImage::from_raw(width, height, data)
        .expect("3 values per pixel")
        .save(&path)
        .expect("write exr");
    path
}

/// The value printed after `name` on its own line of `rondo diff`'s output.
fn printed(stdout: &str, name: &str) -> f64 {
    stdout
        .lines()
        .find_map(|l| l.strip_prefix(name))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no `{name}` in:\n{stdout}"))
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn diff_of_an_image_with_itself_is_exactly_zero() {
    let dir = temp_dir("diff-same");
    let data: Vec<f32> = (0..4 * 3 * 3)
        .map(|i| (i as f32 * 0.37).sin().abs() * 3.0)
        .collect();
    let a = write_exr(&dir, "a.exr", 4, 3, data);
    let out = rondo(&["diff", s(&a), s(&a)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for name in ["rmse", "rel_mse", "mae"] {
        assert_eq!(printed(&stdout, name), 0.0, "{name}:\n{stdout}");
    }
}

#[test]
fn diff_of_images_of_different_sizes_is_a_clear_error() {
    let dir = temp_dir("diff-size");
    let a = write_exr(&dir, "a.exr", 4, 3, vec![0.5; 36]);
    let r = write_exr(&dir, "r.exr", 3, 4, vec![0.5; 36]);
    let out = rondo(&["diff", s(&a), s(&r)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // Exit status 1 from the error path, not 101 from a panic.
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("a.exr") && stderr.contains("4×3") && stderr.contains("3×4"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    // A missing file names the file.
    let missing = dir.join("missing.exr");
    let out = rondo(&["diff", s(&missing), s(&r)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.exr"));
}

#[test]
fn diff_of_a_known_small_difference_gives_the_hand_computed_figures() {
    // Two pixels, six channel values. The reference is (0.5, 0.5, 0.5) and (0, 0, 0); the image
    // differs by +0.125 in the first red and +0.25 in the second blue (values exact in f32).
    //   squared errors: 0.015625 and 0.0625, sum 0.078125 over 6 values
    //   RMSE    = √(0.078125 / 6)                                   = 0.1141088…
    //   relMSE  = (0.015625 / (0.25 + 0.01) + 0.0625 / (0 + 0.01)) / 6 = 1.0516827…
    //   MAE     = (0.125 + 0.25) / 6                                 = 0.0625
    let dir = temp_dir("diff-known");
    let r = write_exr(&dir, "r.exr", 2, 1, vec![0.5, 0.5, 0.5, 0.0, 0.0, 0.0]);
    let a = write_exr(&dir, "a.exr", 2, 1, vec![0.625, 0.5, 0.5, 0.0, 0.0, 0.25]);
    let err_png = dir.join("err.png");
    let out = rondo(&["diff", s(&a), s(&r), "--error-image", s(&err_png)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(REL_EPSILON, 0.01);
    let close = |got: f64, want: f64| (got - want).abs() <= 1e-6 * want;
    assert!(close(printed(&stdout, "rmse"), 0.114_108_8), "{stdout}");
    assert!(close(printed(&stdout, "rel_mse"), 1.051_682_7), "{stdout}");
    assert!(close(printed(&stdout, "mae"), 0.0625), "{stdout}");
    // The error image has the images' size; the pixel with the larger error is the brighter.
    let picture = image::open(&err_png).expect("error image").to_rgb8();
    assert_eq!(picture.dimensions(), (2, 1));
    let luma = |x: u32| {
        picture
            .get_pixel(x, 0)
            .0
            .iter()
            .map(|&c| u32::from(c))
            .sum::<u32>()
    };
    assert!(luma(1) > luma(0));
    // The library gives the same figures.
    let m = compare(&Image::read(&a).expect("a"), &Image::read(&r).expect("r")).expect("sizes");
    assert!(close(m.rmse, (0.078_125f64 / 6.0).sqrt()));
    assert!(close(m.rel_mse, (0.015_625 / 0.26 + 0.0625 / 0.01) / 6.0));
    assert!(close(m.mae, 0.375 / 6.0));
}

#[test]
fn bench_accuracy_smoke_run_writes_its_csv_chart_and_summary() {
    // A 16×16 reference of the Cornell box and a two-level sweep: checks that the command
    // works end to end, not how fast anything is.
    let dir = temp_dir("bench-accuracy");
    let scene = scenes_dir().join("cornell.ron");
    let reference = dir.join("ref.exr");
    let out = rondo(&[
        "render",
        s(&scene),
        "-o",
        s(&reference),
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "256",
        "--seed",
        "0",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let results = dir.join("acc");
    let out = rondo(&[
        "bench",
        "accuracy",
        s(&scene),
        "--reference",
        s(&reference),
        "--out",
        s(&results),
        "--spp-list",
        "1,8",
        "--methods",
        "naive,nee,mis",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let csv = std::fs::read_to_string(results.join("accuracy.csv")).expect("csv");
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some(
            "method,spp,seed,seconds,rmse,rel_mse,mae,sampler,denoised,lamp_out_rmse,image,fireflies"
        )
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 6, "{csv}");
    for method in ["naive", "nee", "mis"] {
        let rmse_at = |spp: &str| -> f64 {
            rows.iter()
                .find(|r| r[0] == method && r[1] == spp)
                .unwrap_or_else(|| panic!("no {method} at {spp} spp:\n{csv}"))[4]
                .parse()
                .expect("rmse")
        };
        let (one, eight) = (rmse_at("1"), rmse_at("8"));
        assert!(one.is_finite() && eight > 0.0, "{csv}");
        // Eight times the samples: about √8 ≈ 2.8 times less error, certainly less.
        assert!(eight < one, "{method}: {one} at 1 spp, {eight} at 8 spp");
    }
    let svg = std::fs::read_to_string(results.join("accuracy.svg")).expect("svg");
    assert!(svg.starts_with("<svg") && svg.contains("slope"), "{svg}");
    let summary = std::fs::read_to_string(results.join("summary.md")).expect("summary");
    assert!(summary.contains("| mis sobol |"), "{summary}");

    // A reference of another size than the scene's is fine (the renders take its size), but
    // a missing reference is an error naming it.
    let out = rondo(&[
        "bench",
        "accuracy",
        s(&scene),
        "--reference",
        s(&dir.join("nope.exr")),
        "--out",
        s(&results),
        "--spp-list",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope.exr"));
}

#[test]
fn bench_accuracy_denoise_measures_a_denoised_twin_of_every_render_and_keeps_the_images() {
    if common::denoiser().is_none() {
        return;
    }
    // A 32×32 Cornell box at 1 and 2 spp: checks the rows, files and figures, not the times.
    let dir = temp_dir("bench-accuracy-denoise");
    let scene = scenes_dir().join("cornell.ron");
    let reference = dir.join("ref.exr");
    let size = ["--width", "32", "--height", "32"];
    let args = ["render", s(&scene), "-o", s(&reference), "--spp", "64"];
    let out = rondo(&[&args[..], &size[..]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (results, images) = (dir.join("acc"), dir.join("images"));
    let out = rondo(&[
        "bench",
        "accuracy",
        s(&scene),
        "--reference",
        s(&reference),
        "--out",
        s(&results),
        "--spp-list",
        "1,2",
        "--methods",
        "mis",
        "--denoise",
        "--keep-images",
        s(&images),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let csv = std::fs::read_to_string(results.join("accuracy.csv")).expect("csv");
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 4, "{csv}");
    let reference = Image::read(&reference).expect("reference");
    for spp in ["1", "2"] {
        let find = |denoised: &str| {
            rows.iter()
                .find(|r| r[1] == spp && r[8] == denoised)
                .unwrap_or_else(|| panic!("no row at {spp} spp, denoised {denoised}:\n{csv}"))
        };
        let (raw, den) = (find("false"), find("true"));
        // The twin is the same render (same seed), denoised.
        assert_eq!(raw[2], den[2], "{csv}");
        assert_eq!(raw[10], format!("mis_sobol_{spp}spp.exr"));
        assert_eq!(den[10], format!("mis_sobol_{spp}spp_denoised.exr"));
        // Each row's figures are those of its kept image against the reference.
        for r in [raw, den] {
            let image = Image::read(&images.join(r[10])).expect("kept image");
            let m = compare(&image, &reference).expect("size");
            let lamp_out = lamp_out_rmse(&image, &reference).expect("size");
            let close = |field: &str, want: f64| {
                let got: f64 = field.parse().expect("a number");
                assert!(
                    (got - want).abs() <= 1e-5 * want,
                    "{got} against {want}\n{csv}"
                );
            };
            close(r[4], m.rmse);
            close(r[9], lamp_out);
        }
        // The denoised file keeps the raw colour as its layer `raw`, equal to the raw image.
        let (plain, layered) = (
            exr_channels(&images.join(raw[10])),
            exr_channels(&images.join(den[10])),
        );
        for c in ["R", "G", "B"] {
            assert_eq!(layered[&format!("raw.{c}")], plain[c], "{c}");
            assert_ne!(layered[c], plain[c], "{c}: not denoised");
        }
    }
    let svg = std::fs::read_to_string(results.join("accuracy_lamp_out.svg")).expect("svg");
    assert!(svg.contains("mis sobol + denoiser"), "{svg}");
    let summary = std::fs::read_to_string(results.join("summary.md")).expect("summary");
    assert!(summary.contains("The denoiser is biased"), "{summary}");
    assert!(
        summary.contains("| mis sobol | lamp-out RMSE |"),
        "{summary}"
    );
}
