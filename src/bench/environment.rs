//! `rondo bench environment`: load time and memory of an environment map (the target: a
//! 4096 × 2048 map loaded and built in at most 0.5 s, in 16 bytes per texel; the sampling guide
//! tables add at most half a byte per texel and a few bytes per row and column).
//!
//! A sky of the requested size (a gradient, a darker ground and a small sun of 2·10⁴ times the
//! sky, so the distribution is far from uniform) is generated deterministically and written, in
//! a private temporary directory, as OpenEXR (float RGB, the `image` crate's encoder) and as a
//! Radiance `.hdr` (RLE RGBE). For each format, over `runs` interleaved runs, it times in wall
//! time:
//!
//! - `decode`: reading the file and decoding it to linear RGB floats
//!   ([`AssetCache::decode_environment_pixels`]);
//! - `build`: [`EnvironmentMap::from_linear_vec`] on those floats (validation and the sampling
//!   tables), as [`AssetCache::environment`] builds the map;
//! - `total`: [`AssetCache::environment`] on a fresh cache, what a scene load pays (read, hash,
//!   decode, build).
//!
//! It also reports the map's [`EnvironmentMap::bytes`] per texel and the peak of the process's
//! resident memory during a `total` above the resident memory before it (`VmHWM` and `VmRSS` of
//! `/proc/self/status`, the peak reset through `/proc/self/clear_refs`; Linux only, else `—`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::scene::assets::AssetCache;
use crate::sky::EnvironmentMap;

/// The map's formats, as file extensions.
pub const FORMATS: [&str; 2] = ["exr", "hdr"];

/// The figures of one format.
#[derive(Clone, Debug)]
pub struct Row {
    /// The file's extension (`exr` or `hdr`).
    pub format: &'static str,
    /// The file's size in bytes.
    pub file_bytes: u64,
    /// Reading and decoding, one per run.
    pub decode: Vec<Duration>,
    /// Building the map from the decoded floats, one per run.
    pub build: Vec<Duration>,
    /// [`AssetCache::environment`] on a fresh cache, one per run.
    pub total: Vec<Duration>,
    /// [`EnvironmentMap::bytes`] of the loaded map.
    pub map_bytes: usize,
    /// Texels of the map.
    pub texels: u64,
    /// Largest peak resident memory during a `total` above the resident memory before it, in
    /// bytes; `None` where `/proc/self` cannot tell.
    pub peak_rss_increase: Option<u64>,
}

/// The sky's linear RGB floats, row-major from the top row, in the map convention of
/// [`crate::sky::environment`]: a blue gradient above the horizon, a dim ground below, and a sun
/// 35° high of 0.5° angular radius (at least one texel wide).
pub fn sky(width: u32, height: u32) -> Vec<f32> {
    use std::f64::consts::PI;
    let (elevation, azimuth) = (35f64.to_radians(), 1.2f64);
    let sun = [
        elevation.cos() * azimuth.sin(),
        elevation.sin(),
        -elevation.cos() * azimuth.cos(),
    ];
    let texel = PI / f64::from(height);
    let cos_radius = 0.5f64.to_radians().max(texel).cos();
    let mut pixels = Vec::with_capacity(3 * width as usize * height as usize);
    for y in 0..height {
        let theta = PI * (f64::from(y) + 0.5) / f64::from(height);
        let (sin_t, cos_t) = theta.sin_cos();
        for x in 0..width {
            let phi = 2.0 * PI * (f64::from(x) + 0.5) / f64::from(width);
            let d = [sin_t * phi.sin(), cos_t, -sin_t * phi.cos()];
            let rgb = if d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2] >= cos_radius {
                [20_000.0, 19_000.0, 17_000.0]
            } else if cos_t > 0.0 {
                let t = cos_t.powf(0.5);
                [0.9 - 0.6 * t, 0.95 - 0.45 * t, 1.0]
            } else {
                [0.25, 0.2, 0.15]
            };
            pixels.extend(rgb.map(|c| c as f32));
        }
    }
    pixels
}

/// A key of `/proc/self/status` in bytes (its values are in kB).
fn status_bytes(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace()
        .nth(1)?
        .parse::<u64>()
        .ok()
        .map(|kib| kib * 1024)
}

/// Resets the process's peak resident memory to its current one (Linux ≥ 4.0).
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// The median and the minimum of `times` (not empty).
pub fn median_min(times: &[Duration]) -> (Duration, Duration) {
    let mut sorted = times.to_vec();
    sorted.sort();
    (
        sorted.get(sorted.len() / 2).copied().unwrap_or_default(),
        sorted.first().copied().unwrap_or_default(),
    )
}

/// Generates the `width` × `height` sky in `dir` in every format and measures each over `runs`
/// runs (interleaved), calling `each` with a line per run.
pub fn run(
    width: u32,
    height: u32,
    runs: usize,
    dir: &Path,
    mut each: impl FnMut(&str),
) -> Result<Vec<Row>, String> {
    let texels = u64::from(width) * u64::from(height);
    if texels == 0 || texels > crate::sky::environment::MAX_TEXELS {
        return Err(format!(
            "a {width}×{height} map: between 1 and {} texels are accepted",
            crate::sky::environment::MAX_TEXELS
        ));
    }
    let image = image::Rgb32FImage::from_raw(width, height, sky(width, height))
        .ok_or("the generated sky does not fit its size")?;
    let mut rows = Vec::new();
    for format in FORMATS {
        let path = dir.join(format!("sky.{format}"));
        let kind = image::ImageFormat::from_extension(format).ok_or("unknown format")?;
        image
            .save_with_format(&path, kind)
            .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
        let file_bytes = std::fs::metadata(&path)
            .map_err(|e| format!("{}: {e}", path.display()))?
            .len();
        rows.push(Row {
            format,
            file_bytes,
            decode: Vec::new(),
            build: Vec::new(),
            total: Vec::new(),
            map_bytes: 0,
            texels,
            peak_rss_increase: None,
        });
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    for k in 0..runs.max(1) {
        for row in &mut rows {
            let path = dir.join(format!("sky.{}", row.format));
            let fail = |e: String| format!("{}: {e}", path.display());

            let start = Instant::now();
            let bytes = std::fs::read(&path).map_err(|e| fail(e.to_string()))?;
            let (w, h, pixels) =
                AssetCache::decode_environment_pixels(&path, &bytes).map_err(fail)?;
            let decode = start.elapsed();
            drop(bytes);
            let start = Instant::now();
            let map = EnvironmentMap::from_linear_vec(w, h, pixels).map_err(fail)?;
            let build = start.elapsed();
            drop(map);

            let before = status_bytes("VmRSS:").filter(|_| reset_peak());
            let start = Instant::now();
            let map = AssetCache::default().environment(&path).map_err(fail)?;
            let total = start.elapsed();
            if let (Some(before), Some(peak)) = (before, status_bytes("VmHWM:")) {
                let increase = peak.saturating_sub(before);
                row.peak_rss_increase = Some(row.peak_rss_increase.unwrap_or(0).max(increase));
            }
            row.map_bytes = map.bytes();
            drop(map);
            each(&format!(
                "run {}, {}: decode {:.1} ms, build {:.1} ms, total {:.1} ms",
                k + 1,
                row.format,
                ms(decode),
                ms(build),
                ms(total)
            ));
            row.decode.push(decode);
            row.build.push(build);
            row.total.push(total);
        }
    }
    Ok(rows)
}

/// The Markdown table of `rows` for a `width` × `height` map, with the `command` that made it.
pub fn markdown(rows: &[Row], width: u32, height: u32, command: &str) -> String {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let runs = rows.first().map_or(0, |r| r.total.len());
    let mut s = format!(
        "Environment map {width}×{height}, median (min) of {runs} runs, wall time; `{command}`\n\n\
         | format | file MB | decode ms | build ms | total ms | map bytes/texel | map MiB | peak RSS increase MiB |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for r in rows {
        let cell = |times: &[Duration]| {
            let (median, min) = median_min(times);
            format!("{:.1} ({:.1})", ms(median), ms(min))
        };
        let peak = r.peak_rss_increase.map_or("—".to_string(), |b| {
            format!("{:.1}", b as f64 / 1048576.0)
        });
        let _ = writeln!(
            s,
            "| {} | {:.1} | {} | {} | {} | {:.2} | {:.1} | {peak} |",
            r.format,
            r.file_bytes as f64 / 1e6,
            cell(&r.decode),
            cell(&r.build),
            cell(&r.total),
            r.map_bytes as f64 / r.texels.max(1) as f64,
            r.map_bytes as f64 / 1048576.0,
        );
    }
    s.push_str(
        "\ndecode: read + decode to linear RGB; build: `EnvironmentMap::from_linear_vec`; total: \
         `AssetCache::environment` on a fresh cache (read, hash, decode, build), what a scene \
         load pays. Peak RSS increase: VmHWM during a total above VmRSS before it.\n",
    );
    s
}

/// `rondo bench environment`: a line per run on stderr; returns the table, which with `out`
/// is also written to `out/environment.md` (returned as the second value).
pub fn main(
    width: u32,
    height: u32,
    runs: usize,
    out: Option<&Path>,
    command: &str,
) -> Result<(String, Option<PathBuf>), String> {
    // A private directory of a fresh, unpredictable name, removed with its contents when
    // dropped.
    let temp = tempfile::Builder::new()
        .prefix("rondo-bench-environment-")
        .tempdir()
        .map_err(|e| format!("cannot create a temporary directory: {e}"))?;
    let rows = run(width, height, runs, temp.path(), |line| eprintln!("{line}"))?;
    drop(temp);
    let table = markdown(&rows, width, height, command);
    let written = match out {
        Some(dir) => {
            let path = dir.join("environment.md");
            crate::output_file::write_bytes(&path, table.as_bytes())
                .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
            Some(path)
        }
        None => None,
    };
    Ok((table, written))
}
