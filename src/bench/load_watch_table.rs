//! `rondo bench load --watch-sizes`: watch-mode edit latency per kind of edit over the `flat`
//! scenes of [`super::load`], with and without a big generated OBJ, and the growth per 10×.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::time::Duration;

use super::load::generate;
use super::load_watch::{KINDS, Kind, find_edits};
use super::load_watch_time::{Interrupt, Timing, median_min, time_edits};
use crate::Overrides;
use crate::watch::WatchOptions;

/// Largest `--big-mesh` (triangles): about 1.5 GB of OBJ.
pub const MAX_BIG_MESH: usize = 20_000_000;

/// What the watch table measures.
#[derive(Clone, Debug, Default)]
pub struct WatchTable {
    /// Entity counts of the flat scenes.
    pub sizes: Vec<usize>,
    /// If set, every size is measured again with an OBJ of about this many triangles placed
    /// once (generated once, `v`, `vn` and `f a//a …` lines: 1,000,000 triangles are ~80 MB).
    pub big_mesh: Option<usize>,
    /// Saves timed per kind of edit.
    pub edits: usize,
}

/// The figures of one scene.
#[derive(Clone, Debug)]
pub struct WatchRow {
    /// Entities: flat named spheres (one fewer with the mesh, which comes first).
    pub entities: usize,
    /// Triangles of the big mesh, if the scene has it.
    pub mesh: Option<usize>,
    /// Scene file size in bytes.
    pub bytes: usize,
    /// From starting the watch to its first image.
    pub cold: Duration,
    /// Each kind of edit.
    pub timings: Vec<Timing>,
}

/// Writes an OBJ height field of at least `triangles` triangles with vertex normals to `path`;
/// returns its triangle count.
pub fn write_big_obj(path: &Path, triangles: usize) -> Result<usize, String> {
    if !(2..=MAX_BIG_MESH).contains(&triangles) {
        return Err(format!(
            "a big mesh of {triangles} triangles: expected 2 to {MAX_BIG_MESH}"
        ));
    }
    let quads = triangles.div_ceil(2);
    let side = (quads as f64).sqrt().ceil() as usize + 1;
    let io = |e: std::io::Error| format!("{}: {e}", path.display());
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    let step = 2.0 / (side - 1) as f64;
    for j in 0..side {
        for i in 0..side {
            let (x, z) = (i as f64 * step, j as f64 * step);
            let y = 0.1 * (3.0 * x).sin() * (2.0 * z).cos();
            writeln!(out, "v {x:.6} {y:.6} {z:.6}").map_err(io)?;
        }
    }
    for j in 0..side {
        for i in 0..side {
            let (x, z) = (i as f64 * step, j as f64 * step);
            let (dx, dz) = (
                0.3 * (3.0 * x).cos() * (2.0 * z).cos(),
                -0.2 * (3.0 * x).sin() * (2.0 * z).sin(),
            );
            let len = (dx * dx + 1.0 + dz * dz).sqrt();
            writeln!(out, "vn {:.6} {:.6} {:.6}", -dx / len, 1.0 / len, -dz / len).map_err(io)?;
        }
    }
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let a = j * side + i + 1;
            let (b, c, d) = (a + 1, a + side + 1, a + side);
            writeln!(
                out,
                "f {a}//{a} {b}//{b} {c}//{c}\nf {a}//{a} {c}//{c} {d}//{d}"
            )
            .map_err(io)?;
        }
    }
    out.flush().map_err(io)?;
    Ok(2 * (side - 1) * (side - 1))
}

/// Measures every size of `table` (and with the big mesh, alternating) in scenes under `dir`.
pub fn watch_rows(
    table: &WatchTable,
    dir: &Path,
    interrupt: &Interrupt,
) -> Result<Vec<WatchRow>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let big = dir.join("big.obj");
    let mesh = match table.big_mesh {
        Some(t) => Some(write_big_obj(&big, t)?),
        None => None,
    };
    let mut rows = Vec::new();
    for &n in &table.sizes {
        interrupt.check()?;
        let scene_dir = dir.join(format!("flat-{n}"));
        let plain = generate("flat", n, &scene_dir)?;
        let mut scenes = vec![(plain, None)];
        if let Some(triangles) = mesh {
            // n − 1 spheres and the mesh: n entities, within the limit of a scene at 10⁶.
            let mesh_dir = scene_dir.join("mesh");
            let path = generate("flat", n.saturating_sub(1), &mesh_dir)?;
            let text = std::fs::read_to_string(&path).map_err(|e| e.to_string())?;
            let entity = "        Entity(name: \"big\", material: \"clay\", shape: Mesh(path: \"big.obj\"), transform: Transform(translate: (0, 1, 0))),\n";
            let with_mesh = text.replacen(
                "    entities: [\n",
                &format!("    entities: [\n{entity}"),
                1,
            );
            std::fs::write(&path, with_mesh).map_err(|e| format!("{}: {e}", path.display()))?;
            // A hard link: the mesh is written once for all sizes.
            std::fs::hard_link(&big, mesh_dir.join("big.obj"))
                .map_err(|e| format!("{}: {e}", mesh_dir.display()))?;
            scenes.push((path, Some(triangles)));
        }
        for (path, mesh) in scenes {
            let row = watch_row(&path, n, mesh, table.edits, dir, interrupt)?;
            let ms = |d: Duration| d.as_secs_f64() * 1e3;
            let kinds: Vec<String> = row
                .timings
                .iter()
                .map(|t| {
                    format!(
                        "{} {:.1} ms",
                        t.kind.name(),
                        ms(median_min(&t.first_image).0)
                    )
                })
                .collect();
            eprintln!(
                "watch, flat {n}{}: cold start {:.1} ms; {}",
                if mesh.is_some() { " + big mesh" } else { "" },
                ms(row.cold),
                kinds.join(", ")
            );
            rows.push(row);
        }
        std::fs::remove_dir_all(&scene_dir).ok();
    }
    Ok(rows)
}

/// Times the edits of the scene at `path` (a file of our private directory, rewritten in place).
fn watch_row(
    path: &Path,
    entities: usize,
    mesh: Option<usize>,
    edits: usize,
    dir: &Path,
    interrupt: &Interrupt,
) -> Result<WatchRow, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let found = find_edits(path, &text)?;
    let mut options = WatchOptions::new(path, dir.join("out.png"));
    options.overrides = Overrides {
        width: Some(16),
        height: Some(12),
        spp: Some(1),
        ..Overrides::default()
    };
    let (cold, timings) = time_edits(
        options,
        &text,
        &found,
        edits,
        interrupt,
        |t| std::fs::write(path, t),
        |_| {},
    )?;
    Ok(WatchRow {
        entities,
        mesh,
        bytes: text.len(),
        cold,
        timings,
    })
}

/// The table: a row per scene (without the mesh first, then with it), per kind of edit the
/// median (minimum) from the save to the first image, and the growth factor of the median from
/// the previous size (per 10×: 1 is constant, 10 linear).
pub fn watch_markdown(rows: &[WatchRow], edits: usize) -> String {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mut s = format!(
        "Watch mode, save to first image (16×12, 1 spp): median (min) of {edits} saves per kind in ms, then the growth per 10× from the size above.\n\n\
         | scene | entities | file MB | cold start ms |"
    );
    for k in KINDS {
        let _ = write!(s, " {} |", k.name());
    }
    s.push_str("\n|---|---:|---:|---:|");
    s.push_str(&"---:|".repeat(KINDS.len()));
    s.push('\n');
    let mut sorted: Vec<&WatchRow> = rows.iter().collect();
    sorted.sort_by_key(|r| (r.mesh.is_some(), r.entities));
    for (i, r) in sorted.iter().enumerate() {
        let previous = i
            .checked_sub(1)
            .map(|p| sorted[p])
            .filter(|p| p.mesh.is_some() == r.mesh.is_some() && p.entities > 0);
        let growth = |a: Option<Duration>, b: Duration| match (previous, a) {
            (Some(p), Some(a)) if r.entities > p.entities => {
                let f = (r.entities as f64 / p.entities as f64).log10();
                format!(" ×{:.1}", (ms(b) / ms(a).max(1e-3)).powf(1.0 / f))
            }
            _ => String::new(),
        };
        let scene = match r.mesh {
            Some(t) => format!("flat + {t}-triangle OBJ"),
            None => "flat".into(),
        };
        let _ = write!(
            s,
            "| {scene} | {} | {:.1} | {:.0}{} |",
            r.entities,
            r.bytes as f64 / 1e6,
            ms(r.cold),
            growth(previous.map(|p| p.cold), r.cold)
        );
        for k in KINDS {
            let median = |row: &WatchRow, k: Kind| {
                row.timings
                    .iter()
                    .find(|t| t.kind == k)
                    .map(|t| median_min(&t.first_image))
            };
            match median(r, k) {
                Some((m, min)) => {
                    let before = previous.and_then(|p| median(p, k)).map(|x| x.0);
                    let _ = write!(s, " {:.1} ({:.1}){} |", ms(m), ms(min), growth(before, m));
                }
                None => s.push_str(" – |"),
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_big_mesh_has_the_triangles_asked_for() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("m.obj");
        let triangles = write_big_obj(&path, 1000).expect("written");
        // 23² quads of two triangles: the first square count of at least 500 quads.
        assert_eq!(triangles, 2 * 23 * 23);
        let text = std::fs::read_to_string(&path).expect("read");
        assert_eq!(
            text.lines().filter(|l| l.starts_with("f ")).count(),
            triangles
        );
        assert_eq!(
            text.lines().filter(|l| l.starts_with("vn ")).count(),
            24 * 24
        );
        assert!(write_big_obj(&path, MAX_BIG_MESH + 1).is_err());
    }

    #[test]
    fn growth_compares_consecutive_sizes_of_the_same_scene() {
        let timing = |ms: u64| Timing {
            kind: Kind::Colour,
            target: String::new(),
            first_image: vec![Duration::from_millis(ms)],
            full: Vec::new(),
        };
        let row = |entities, mesh, ms| WatchRow {
            entities,
            mesh,
            bytes: 0,
            cold: Duration::from_millis(ms),
            timings: vec![timing(ms)],
        };
        let rows = [
            row(1000, None, 2),
            row(1000, Some(10), 50),
            row(100_000, None, 200),
        ];
        let table = watch_markdown(&rows, 1);
        let lines: Vec<&str> = table.lines().filter(|l| l.starts_with("| flat")).collect();
        assert_eq!(lines.len(), 3, "{table}");
        // 2 ms → 200 ms over 100×: ×10 per 10×; the mesh row has no size above it.
        assert_eq!(
            lines[0],
            "| flat | 1000 | 0.0 | 2 | 2.0 (2.0) | – | – | – |"
        );
        assert_eq!(
            lines[1],
            "| flat | 100000 | 0.0 | 200 ×10.0 | 200.0 (200.0) ×10.0 | – | – | – |"
        );
        assert!(
            lines[2].starts_with("| flat + 10-triangle OBJ | 1000 |"),
            "{table}"
        );
    }
}
