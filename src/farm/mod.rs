//! Rendering beyond one process: renders of a sample range into a partial, resumes of a
//! partial, and the scheduler script that splits a render over a Slurm job array.
//!
//! Every sample's random numbers depend only on (seed, pixel, sample index) and the film sums
//! exactly ([`crate::film`]), so a render splits into independent sample ranges whose merge
//! ([`crate::farm::partial`]) equals the single-process image bit for bit. See `docs/farm.md`.

pub mod partial;

use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use self::partial::{
    FORMAT_2, PartialError, PartialMeta, Sums, Tracing, image_hash, image_settings, normalize,
    read_partial, setting_difference, write_output,
};
use crate::app::{Overrides, Renderer};
use crate::film::{ALBEDO_SHIFT, DEFAULT_SHIFT, OutputKind, Pixel};
use crate::geometry::layout::LayoutKind;
use crate::scene::error::SceneError;
use crate::scene::format::SettingsDesc;

/// Why a range render or a resume could not start or finish.
#[derive(Debug, thiserror::Error)]
pub enum FarmError {
    /// The scene did not load.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A partial was unusable, or the request was.
    #[error(transparent)]
    Partial(#[from] PartialError),
}

fn fail(message: impl Into<String>) -> FarmError {
    FarmError::Partial(PartialError(message.into()))
}

/// Which samples a render holds beyond a plain `0..spp` render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Samples {
    /// Samples `A..B` of every pixel, written as a partial (`--samples A..B`).
    Range(Range<u32>),
    /// The samples of a partial plus those after it, up to the settings' spp (`--resume P`).
    Resume(PathBuf),
}

/// A render of [`Samples`] that has been loaded and is ready to run; [`PartRender::finish`]
/// writes its result.
#[derive(Debug)]
pub struct PartRender {
    output: PathBuf,
    meta: PartialMeta,
    /// The resumed partial and its sums, read before anything was rendered.
    resume: Option<(PathBuf, Sums)>,
    /// The settings, overrides applied (spp = one past the last sample rendered).
    pub settings: SettingsDesc,
}

/// Loads `scene` into `r` with `overrides` for a render of `samples` into `output`, checking
/// the request: a range needs a `.exr` output and no spp override (the range's end is the spp);
/// a resume needs a partial with the feature buffers (not a [`FORMAT_2`] one) of the same
/// scene, settings (sampler, method, … and `r`'s [`Tracing`]), seed and resolution, and an spp
/// beyond its last sample. The resumed partial is read whole and checked first, before the scene
/// is loaded: a corrupt one is refused before any work, and its sums are held (one more image
/// and its feature buffers in memory, 144 bytes a pixel) until [`PartRender::finish`]. `r` is
/// set to collect the feature buffers, which every partial carries.
pub fn prepare(
    r: &mut Renderer,
    mut overrides: Overrides,
    scene: &Path,
    output: &Path,
    samples: &Samples,
) -> Result<PartRender, FarmError> {
    let exr = OutputKind::from_path(output) == Some(OutputKind::Exr);
    let scene_name = scene
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tracing = Tracing {
        roulette: r.roulette(),
        instancing: r.instancing(),
    };
    r.set_features(true);
    match samples {
        Samples::Range(range) => {
            if overrides.spp.is_some() {
                return Err(fail(
                    "--samples A..B gives the samples to render: leave out --spp",
                ));
            }
            if !exr {
                return Err(fail(format!(
                    "{}: a render of a sample range writes a partial, which must end in .exr",
                    output.display()
                )));
            }
            overrides.spp = Some(range.end);
            r.set_overrides(overrides);
            let info = r.load(scene)?;
            r.set_first_sample(range.start);
            let s = info.settings;
            let settings = image_settings(&s, tracing);
            Ok(PartRender {
                output: output.to_path_buf(),
                meta: PartialMeta {
                    width: s.width,
                    height: s.height,
                    seed: s.seed,
                    hash: image_hash(&info.dependencies, (s.width, s.height), s.seed, &settings)?,
                    ranges: vec![range.clone()],
                    scene: scene_name,
                    shift: DEFAULT_SHIFT,
                    settings,
                    features: true,
                    albedo_shift: ALBEDO_SHIFT,
                },
                resume: None,
                settings: s,
            })
        }
        Samples::Resume(base) => {
            let (held, base_sums) = read_partial(base)?;
            if !held.features {
                return Err(fail(format!(
                    "{}: a {FORMAT_2} partial, without the feature buffers (albedo, normal) this rondo continues too: render it again, or merge it with partials of its format",
                    base.display()
                )));
            }
            if held.albedo_shift != ALBEDO_SHIFT {
                return Err(fail(format!(
                    "{}: its albedo sums are in the colour's units (2^-{}), as an older rondo wrote them, not in 2^-{ALBEDO_SHIFT}: merge it with partials of its kind, or render its samples again",
                    base.display(),
                    held.albedo_shift
                )));
            }
            r.set_overrides(overrides);
            let info = r.load(scene)?;
            let s = info.settings;
            let name = base.display();
            if (held.width, held.height) != (s.width, s.height) {
                return Err(fail(format!(
                    "{name}: rendered at {}x{}, this render is {}x{} (give the same --width/--height)",
                    held.width, held.height, s.width, s.height
                )));
            }
            if held.seed != s.seed {
                return Err(fail(format!(
                    "{name}: rendered with seed {}, this render has seed {} (give the same --seed)",
                    held.seed, s.seed
                )));
            }
            let settings = image_settings(&s, tracing);
            if let Some((key, theirs, mine)) = setting_difference(&held.settings, &settings) {
                let flag = match key {
                    "max_depth" => " (give the same --max-depth)",
                    "method" => " (give the same --method)",
                    "sampler" => " (give the same --sampler)",
                    _ => "",
                };
                return Err(fail(format!(
                    "{name}: rendered with {key} {theirs}, this render has {key} {mine}{flag}"
                )));
            }
            let hash = image_hash(&info.dependencies, (s.width, s.height), s.seed, &settings)?;
            if held.hash != hash {
                return Err(fail(format!(
                    "{name}: made from another scene, scene file or settings (hash {:016x}, this render {hash:016x})",
                    held.hash
                )));
            }
            let start = held.end();
            if start >= s.spp {
                return Err(fail(format!(
                    "{name} already holds samples up to {start}; ask for more with --spp (e.g. --spp {})",
                    start.saturating_mul(2)
                )));
            }
            r.set_first_sample(start);
            let mut ranges = held.ranges.clone();
            ranges.push(start..s.spp);
            Ok(PartRender {
                output: output.to_path_buf(),
                meta: PartialMeta {
                    ranges: normalize(ranges),
                    scene: scene_name,
                    ..held
                },
                resume: Some((base.clone(), base_sums)),
                settings: s,
            })
        }
    }
}

impl PartRender {
    /// The sample ranges the output will hold.
    pub fn ranges(&self) -> &[Range<u32>] {
        &self.meta.ranges
    }

    /// After `r` rendered to completion: adds the resumed partial's sums (colour and feature
    /// buffers), if any, and writes the output (a partial with the feature buffers for `.exr`,
    /// an 8-bit image for `.png`), atomically.
    pub fn finish(mut self, r: &mut Renderer) -> Result<(), FarmError> {
        let film = r.film_mut();
        if let Some((base, _)) = &self.resume
            && self.meta.shift != film.shift
        {
            return Err(fail(format!(
                "{}: its sums are in units of 2^-{}, this render's in 2^-{}",
                base.display(),
                self.meta.shift,
                film.shift
            )));
        }
        self.meta.shift = film.shift;
        let Some(features) = &mut film.features else {
            return Err(fail(format!(
                "{}: the render collected no feature buffers to write",
                self.output.display()
            )));
        };
        if let Some((path, base)) = &self.resume {
            let overflow = || {
                fail(format!(
                    "{}: its sums and those rendered for {} overflow {} bits",
                    path.display(),
                    self.output.display(),
                    32 * Pixel::WORDS
                ))
            };
            for (pixel, held) in film.sum.iter_mut().zip(&base.colour) {
                *pixel = pixel.checked_merge(held).ok_or_else(overflow)?;
            }
            if let Some(held) = &base.features {
                features.checked_merge(held).ok_or_else(overflow)?;
            }
        }
        write_output(&self.output, &self.meta, &film.sum, film.features.as_ref())
            .map_err(|e| fail(format!("{}: cannot write: {e}", self.output.display())))
    }
}

/// Sample range of task `index` of `tasks` over `spp` samples: `[i·spp/K, (i+1)·spp/K)`, the
/// formula the scheduler scripts compute in shell arithmetic.
pub fn task_range(index: u32, tasks: u32, spp: u32) -> Range<u32> {
    let at = |i: u32| (u64::from(i) * u64::from(spp) / u64::from(tasks.max(1))) as u32;
    at(index)..at(index + 1)
}

/// The `rondo render` flags that reproduce `overrides` (but spp, which each task's range
/// replaces) and `layout` in a task.
pub fn render_flags(overrides: &Overrides, layout: LayoutKind) -> Vec<String> {
    // Every field by name: an override added to `Overrides` fails to compile here until it is
    // passed on too, so no task can render with a setting the others lack.
    let Overrides {
        width,
        height,
        spp: _,
        max_depth,
        seed,
        method,
        sampler,
    } = *overrides;
    let mut flags = Vec::new();
    let mut push = |name: &str, value: Option<String>| {
        if let Some(v) = value {
            flags.push(format!("--{name}"));
            flags.push(v);
        }
    };
    push("width", width.map(|v| v.to_string()));
    push("height", height.map(|v| v.to_string()));
    push("max-depth", max_depth.map(|v| v.to_string()));
    push("seed", seed.map(|v| v.to_string()));
    push("method", method.map(|v| v.to_string()));
    push("sampler", sampler.map(|v| v.to_string()));
    if layout != LayoutKind::default() {
        push("layout", Some(layout.to_string()));
    }
    flags
}

/// A render to split over a Slurm job array.
#[derive(Clone, Debug)]
pub struct SlurmJob {
    /// The rondo binary the tasks run (absolute).
    pub rondo: PathBuf,
    /// The scene (absolute).
    pub scene: PathBuf,
    /// The merged image (absolute); the partials go to `<output without extension>.parts/`.
    pub output: PathBuf,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// Array tasks.
    pub tasks: u32,
    /// CPUs (render threads) per task.
    pub cpus_per_task: u32,
    /// `--partition`, if any.
    pub partition: Option<String>,
    /// `--time` limit per task, if any.
    pub time: Option<String>,
    /// Further `rondo render` flags (the overrides, see [`render_flags`]).
    pub render_flags: Vec<String>,
}

/// `text` quoted for bash (single quotes).
pub fn shell_quote(text: &str) -> String {
    if !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c))
    {
        return text.to_string();
    }
    format!("'{}'", text.replace('\'', r"'\''"))
}

fn path_text(path: &Path) -> Result<String, PartialError> {
    let text = path
        .to_str()
        .ok_or_else(|| PartialError(format!("{}: path is not UTF-8", path.display())))?;
    if text.contains('\n') {
        return Err(PartialError(format!("{text:?}: path has a line break")));
    }
    Ok(shell_quote(text))
}

fn slurm_value(what: &str, v: &str) -> Result<String, PartialError> {
    if v.is_empty() || v.chars().any(|c| c.is_whitespace() || c.is_control()) {
        return Err(PartialError(format!("--{what} {v:?}: no spaces allowed")));
    }
    Ok(v.to_string())
}

/// The directory a farm render keeps its partials in: `<output without extension>.parts`.
pub fn parts_dir(output: &Path) -> PathBuf {
    output.with_extension("parts")
}

/// A bash function `q` that prints its argument quoted for any POSIX shell as [`shell_quote`]
/// quotes the script's paths (bare if it holds only safe characters, else in single quotes), so
/// the commands the report prints can be pasted whatever the paths hold.
const QUOTE_FUNCTION: &str = r#"q() {
  case $1 in
    '' | *[!-[:alnum:]_./=:,+@%]*)
      local s=${1//\'/\'\\\'\'}
      printf "'%s'" "$s"
      ;;
    *) printf '%s' "$1" ;;
  esac
}
"#;

/// The sbatch script of `job`: a job array of `tasks` tasks, task `i` rendering
/// [`task_range`]`(i)` into `part-<i>.exr`; the first task to start queues the merge (after the
/// whole array succeeded, `--dependency=afterok`) and a report (after it failed,
/// `afternotok`) that lists each failed task with the commands to rerun it.
pub fn slurm_script(job: &SlurmJob) -> Result<String, PartialError> {
    if job.tasks == 0 || job.tasks > job.spp {
        return Err(PartialError(format!(
            "--tasks {} must be between 1 and the spp ({})",
            job.tasks, job.spp
        )));
    }
    if job.cpus_per_task == 0 {
        return Err(PartialError("--cpus-per-task must be at least 1".into()));
    }
    let stem = job
        .output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    let name = format!("rondo-{name}");
    let mut s = String::new();
    let last = job.tasks - 1;
    let (spp, tasks) = (job.spp, job.tasks);
    let _ = writeln!(s, "#!/bin/bash");
    let _ = writeln!(
        s,
        "# Written by `rondo farm slurm`: {spp} spp of a scene in {tasks} Slurm array tasks, then one merge."
    );
    s.push_str(
        "#
#   sbatch render.sbatch              submit; the first task to start queues the merge
#   sbatch --array=3,7 render.sbatch  rerun tasks 3 and 7; a new merge then runs after them
#
# Task i renders samples [i*SPP/TASKS, (i+1)*SPP/TASKS) into $PARTS/part-<i>.exr (a partial,
# docs/partial-format.md). The merge runs after the whole array succeeded (afterok); if a task
# failed, a report job runs instead (afternotok) and lists each failed task with the commands
# to rerun it. Logs: NAME-<array job>_<task>.out, NAME-merge-<job>.out, NAME-report-<job>.out
# in the submit directory.
",
    );
    let _ = writeln!(s, "#SBATCH --job-name={name}");
    let _ = writeln!(s, "#SBATCH --array=0-{last}");
    let _ = writeln!(s, "#SBATCH --cpus-per-task={}", job.cpus_per_task);
    let _ = writeln!(s, "#SBATCH --output={name}-%A_%a.out");
    if let Some(p) = &job.partition {
        let _ = writeln!(s, "#SBATCH --partition={}", slurm_value("partition", p)?);
    }
    if let Some(t) = &job.time {
        let _ = writeln!(s, "#SBATCH --time={}", slurm_value("time", t)?);
    }
    let flags: Vec<String> = job.render_flags.iter().map(|f| shell_quote(f)).collect();
    let _ = write!(
        s,
        "set -euo pipefail

RONDO={rondo}
SCENE={scene}
OUTPUT={output}
PARTS={parts}
SPP={spp}
TASKS={tasks}
FLAGS=({flags})
NAME={name}

range() {{ echo \"$(( $1 * SPP / TASKS ))..$(( ($1 + 1) * SPP / TASKS ))\"; }}
part() {{ printf '%s/part-%04d.exr' \"$PARTS\" \"$1\"; }}
{QUOTE_FUNCTION}
case \"${{RONDO_FARM_STEP:-render}}\" in
merge)
  exec \"$RONDO\" merge --spp \"$SPP\" -o \"$OUTPUT\" \"$PARTS\"/part-*.exr
  ;;
report)
  echo \"rondo: tasks of array job $RONDO_FARM_ARRAY failed, so the merge did not run.\"
  failed=()
  for ((i = 0; i < TASKS; i++)); do
    p=$(part \"$i\")
    if [[ ! -f $p || ! -s $p || -e $p.failed ]]; then
      failed+=(\"$i\")
      echo \"task $i (samples $(range \"$i\")) failed$(cat \"$p.failed\" 2>/dev/null || true); rerun it alone with:\"
      cmd=\"$(q \"$RONDO\") render $(q \"$SCENE\") --samples $(range \"$i\") -o $(q \"$p\")\"
      for f in \"${{FLAGS[@]}}\"; do cmd+=\" $(q \"$f\")\"; done
      echo \"  $cmd\"
    fi
  done
  list=$(IFS=,; echo \"${{failed[*]}}\")
  echo \"or rerun them all, then the merge, with:\"
  echo \"  sbatch --array=$list $(q \"$RONDO_FARM_SCRIPT\")\"
  exit 1
  ;;
esac

i=$SLURM_ARRAY_TASK_ID
p=$(part \"$i\")
trap 'code=$?; if [ $code -ne 0 ]; then echo \" with exit code $code on $(hostname)\" > \"$p.failed\"; fi' EXIT
mkdir -p \"$PARTS\"
rm -f \"$p.failed\" \"$p\"
if [[ $i == \"${{SLURM_ARRAY_TASK_MIN:-0}}\" ]]; then
  script=$(scontrol show job \"$SLURM_JOB_ID\" 2>/dev/null | sed -n 's/^ *Command=//p' | head -n 1)
  export RONDO_FARM_SCRIPT=${{script:-render.sbatch}} RONDO_FARM_ARRAY=$SLURM_ARRAY_JOB_ID
  merge=$(RONDO_FARM_STEP=merge sbatch --parsable --array=0 --job-name=\"$NAME-merge\" \\
    --output=\"$NAME-merge-%A.out\" --dependency=\"afterok:$SLURM_ARRAY_JOB_ID\" \\
    --kill-on-invalid-dep=yes \"$0\")
  report=$(RONDO_FARM_STEP=report sbatch --parsable --array=0 --job-name=\"$NAME-report\" \\
    --output=\"$NAME-report-%A.out\" --dependency=\"afternotok:$SLURM_ARRAY_JOB_ID\" \\
    --kill-on-invalid-dep=yes \"$0\")
  echo \"rondo: merge job $merge runs once array job $SLURM_ARRAY_JOB_ID succeeded; report job $report if it fails\"
fi
\"$RONDO\" render \"$SCENE\" --samples \"$(range \"$i\")\" -o \"$p\" \\
  --threads \"${{SLURM_CPUS_PER_TASK:-1}}\" \"${{FLAGS[@]}}\"
",
        rondo = path_text(&job.rondo)?,
        scene = path_text(&job.scene)?,
        output = path_text(&job.output)?,
        parts = path_text(&parts_dir(&job.output))?,
        flags = flags.join(" "),
    );
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn task_ranges_tile_the_samples() {
        for (spp, tasks) in [(4096, 16), (10, 3), (7, 7), (1, 1), (u32::MAX, 5)] {
            let ranges: Vec<_> = (0..tasks).map(|i| task_range(i, tasks, spp)).collect();
            assert_eq!(ranges[0].start, 0);
            assert_eq!(ranges.last().map(|r| r.end), Some(spp));
            assert!(ranges.windows(2).all(|w| w[0].end == w[1].start));
            assert!(ranges.iter().all(|r| r.start < r.end));
        }
    }

    #[test]
    fn quoting_survives_spaces_and_quotes() {
        assert_eq!(shell_quote("/a/b.ron"), "/a/b.ron");
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
        assert_eq!(shell_quote(""), "''");
    }
}
