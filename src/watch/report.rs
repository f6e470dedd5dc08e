//! What the watch loop reports: the line per reload and the events an observer sees.

use std::fmt;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use crate::ecs::resources::{ChangeSummary, Counters};
use crate::film::Film;
use crate::scene::error::{MAX_MESSAGE, SceneError, escape_controls, printable};

/// What one (re)load changed, rebuilt and cost: the line printed per reload.
#[derive(Clone, Debug, PartialEq)]
pub struct ReloadReport {
    /// 0 for the first load, then 1, 2, … for each successful reload.
    pub number: u64,
    /// The changed files that caused it (empty for the first load).
    pub trigger: Vec<PathBuf>,
    /// Whether its first frame ran (the scene was applied to the world); a reload superseded
    /// before that hands its changes on to the next one.
    pub applied: bool,
    /// What the scene diff changed in the world.
    pub changes: ChangeSummary,
    /// Whether the geometry and its BVH were rebuilt (at once, or after a refitted preview).
    pub bvh_rebuilt: bool,
    /// Whether the first frame refitted the BVH to moved primitives for the preview (the build
    /// follows before real samples: see `systems::rebuild_geometry`).
    pub bvh_refit: bool,
    /// Primitives in the geometry.
    pub primitives: usize,
    /// Whether material assignments were rebuilt.
    pub materials_synced: bool,
    /// Image textures decoded by the load (unchanged textures come from the cache).
    pub textures_decoded: u64,
    /// Environment maps decoded and given their distribution by the load (an unchanged map
    /// comes from the cache).
    pub environments_built: u64,
    /// Bytes of asset files (textures, meshes, maps, glTF files and buffers) the load read: an
    /// unchanged file is not read again.
    pub asset_bytes_read: u64,
    /// Reading, parsing and validating the scene, textures included.
    pub parse: Duration,
    /// Applying the scene to the world and assigning materials (the BVH excluded).
    pub ecs: Duration,
    /// Packing geometry and building (or refitting) the BVH (zero if neither).
    pub bvh: Duration,
    /// The first pass: its sample count and duration.
    pub first_pass: Option<(u32, Duration)>,
    /// Whether the first pass was the reduced-resolution preview (one sample per block).
    pub preview: bool,
    /// From the save to the first image written.
    pub first_image: Option<Duration>,
    /// From the save to the full-quality image written; `None` if superseded by a newer save.
    pub full: Option<Duration>,
    /// Samples per pixel of the last image written.
    pub samples: u32,
    /// Samples per pixel the scene asks for.
    pub spp: u32,
    /// Passes abandoned (cancelled) and started over.
    pub restarts: u32,
    /// The renderer's counters when the report was made.
    pub counters: Counters,
}

impl ReloadReport {
    /// The report of reload `number` of a scene of `spp` samples, before anything happened.
    pub(super) fn started(number: u64, trigger: Vec<PathBuf>, spp: u32) -> Self {
        Self {
            number,
            trigger,
            applied: false,
            changes: ChangeSummary::default(),
            bvh_rebuilt: false,
            bvh_refit: false,
            primitives: 0,
            materials_synced: false,
            textures_decoded: 0,
            environments_built: 0,
            asset_bytes_read: 0,
            parse: Duration::ZERO,
            ecs: Duration::ZERO,
            bvh: Duration::ZERO,
            first_pass: None,
            preview: false,
            first_image: None,
            full: None,
            samples: 0,
            spp,
            restarts: 0,
            counters: Counters::default(),
        }
    }

    /// Whether the render reached the scene's spp (not superseded).
    pub fn completed(&self) -> bool {
        self.full.is_some()
    }
}

/// Formats a duration for humans: `0.42 ms`, `12.3 ms`, `2.31 s`.
fn human(d: Duration) -> String {
    let ms = d.as_secs_f64() * 1e3;
    if ms < 10.0 {
        format!("{ms:.2} ms")
    } else if ms < 1000.0 {
        format!("{ms:.1} ms")
    } else {
        format!("{:.2} s", ms / 1e3)
    }
}

impl fmt::Display for ReloadReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.number == 0 {
            write!(f, "loaded: ")?;
        } else {
            write!(f, "reload {}: ", self.number)?;
        }
        if !self.applied {
            let names: Vec<String> = self
                .trigger
                .iter()
                .map(|p| {
                    let name = p.file_name().unwrap_or(p.as_os_str()).to_string_lossy();
                    escape_controls(&name).into_owned()
                })
                .collect();
            let names = if names.is_empty() {
                "files".to_string()
            } else {
                names.join(", ")
            };
            return write!(
                f,
                "{names} changed | superseded by a newer save before its first frame"
            );
        }
        let c = &self.changes;
        let mut changed = Vec::new();
        for (n, what) in [
            (c.added, "added"),
            (c.changed, "changed"),
            (c.removed, "removed"),
        ] {
            if n > 0 {
                let s = if n == 1 { "entity" } else { "entities" };
                changed.push(format!("{n} {s} {what}"));
            }
        }
        for (flag, what) in [
            (c.reordered, "entities reordered"),
            (c.materials, "materials"),
            (c.camera, "camera"),
            (c.settings, "settings"),
            (c.sky, "sky"),
            (c.lights, "lights"),
        ] {
            if flag {
                changed.push(what.to_string());
            }
        }
        if changed.is_empty() {
            changed.push("no changes".into());
        }
        let mut rebuilt = Vec::new();
        match (self.bvh_refit, self.bvh_rebuilt) {
            (true, true) => rebuilt.push(format!(
                "BVH boxes refit for the preview, then the BVH ({} primitives)",
                self.primitives
            )),
            (true, false) => rebuilt.push(format!(
                "BVH boxes refit for the preview ({} primitives)",
                self.primitives
            )),
            (false, true) => rebuilt.push(format!("BVH ({} primitives)", self.primitives)),
            (false, false) => {}
        }
        if self.materials_synced {
            rebuilt.push("materials".into());
        }
        if self.textures_decoded > 0 {
            rebuilt.push(format!("{} texture(s) decoded", self.textures_decoded));
        }
        if self.environments_built > 0 {
            rebuilt.push("environment map".into());
        }
        let rebuilt = if rebuilt.is_empty() {
            "nothing".to_string()
        } else {
            rebuilt.join(", ")
        };
        write!(f, "{} | rebuilt {rebuilt} | ", changed.join(", "))?;
        write!(f, "parse {}, ECS {}, ", human(self.parse), human(self.ecs))?;
        if self.bvh_refit {
            write!(f, "BVH refit {}, ", human(self.bvh))?;
        } else if self.bvh_rebuilt {
            write!(f, "BVH {}, ", human(self.bvh))?;
        } else {
            write!(f, "BVH -, ")?;
        }
        match self.first_pass {
            Some((_, d)) if self.preview => write!(f, "first pass {} (preview), ", human(d))?,
            Some((spp, d)) => write!(f, "first pass {} ({spp} spp), ", human(d))?,
            None => write!(f, "first pass -, ")?,
        }
        let since = if self.number == 0 {
            "since start"
        } else {
            "since save"
        };
        if let Some(d) = self.first_image {
            write!(f, "first image {} {since}, ", human(d))?;
        }
        match self.full {
            Some(d) => write!(f, "full {} ({} spp)", human(d), self.spp)?,
            None => write!(f, "superseded at {}/{} spp", self.samples, self.spp)?,
        }
        if self.restarts > 0 {
            write!(f, ", {} restart(s)", self.restarts)?;
        }
        Ok(())
    }
}

/// What the loop did, for the command line to print, tests to wait on and observers (see the
/// module docs, "The event point").
#[derive(Clone, Debug)]
pub enum Report {
    /// The set of watched files changed.
    Watching {
        /// Files watched.
        files: usize,
        /// Their directories.
        directories: Vec<PathBuf>,
    },
    /// A save loaded; its render starts (the reload is not applied to the world yet).
    Started {
        /// The reload ([`ReloadReport::number`]).
        reload: u64,
        /// The changed files that caused it (empty for the first load).
        trigger: Vec<PathBuf>,
        /// Samples per pixel the scene asks for.
        spp: u32,
        /// When the save happened (the latest file event).
        saved: Instant,
    },
    /// A pass improved the image and it was written (an observer gets the film with it).
    Wrote {
        /// The reload it belongs to ([`ReloadReport::number`]).
        reload: u64,
        /// Samples per pixel in it (1 for the preview).
        samples: u32,
        /// Whether it is the reduced-resolution preview.
        preview: bool,
        /// Samples per pixel the scene asks for.
        spp: u32,
        /// What the reload changed in the world.
        changes: ChangeSummary,
        /// Whether this is the first image of a scene other than the last image written: the
        /// scene changed since, by this reload or by one superseded before it wrote any.
        new_scene: bool,
        /// When the write finished.
        at: Instant,
    },
    /// A render finished, or was superseded by a newer save.
    Rendered(ReloadReport),
    /// A save could not be loaded; the previous scene and image are kept. The error's file,
    /// line, column and field are its own fields; its message is at most [`MAX_MESSAGE`] bytes,
    /// control characters escaped, and the line it quotes comes from a scene or prefab file
    /// only ([`SceneError::source_line`]).
    Failed(Box<SceneError>),
    /// A load failed but the save may not be over: the error is reported only if no further
    /// event comes within three windows. Not printed.
    Deferred {
        /// The error so far.
        message: String,
    },
    /// The scene file is gone; the loop waits for it to come back.
    SceneMissing {
        /// The scene file.
        path: PathBuf,
    },
    /// Something went wrong that does not stop watching (an unwatchable directory, a failed
    /// image write, a watcher error).
    Warning {
        /// What.
        message: String,
    },
    /// A pass was denoised (see [`super::Watch::set_denoise_sink`]): shown in the viewer, and
    /// written if the output is denoised.
    Denoised(crate::denoise::Denoised),
}

impl Report {
    /// The line the command line prints, if any (starts, image writes and deferred errors are
    /// silent). Control characters of file names and messages are escaped.
    pub fn line(&self) -> Option<String> {
        let line = self.raw_line()?;
        Some(printable(&line, 2 * MAX_MESSAGE).into_owned())
    }

    fn raw_line(&self) -> Option<String> {
        Some(match self {
            Self::Watching { files, directories } => {
                let dirs: Vec<String> = directories
                    .iter()
                    .map(|d| d.display().to_string())
                    .collect();
                format!(
                    "watching {files} file(s) in {} (Ctrl-C to stop)",
                    dirs.join(", ")
                )
            }
            Self::Started { .. } | Self::Wrote { .. } | Self::Deferred { .. } => return None,
            Self::Rendered(r) => r.to_string(),
            Self::Failed(error) => {
                format!("error: {error} (keeping the last good image; fix and save again)")
            }
            Self::SceneMissing { path } => {
                format!("{}: deleted; waiting for it to come back", path.display())
            }
            Self::Warning { message } => format!("warning: {message}"),
            Self::Denoised(d) => {
                let wrote = d.wrote.as_ref().map_or(String::new(), |p| {
                    format!(
                        ", wrote {}",
                        p.file_name().unwrap_or_default().to_string_lossy()
                    )
                });
                format!(
                    "reload {}: denoised {} spp in {} ({}), {} after the save{wrote}",
                    d.reload,
                    d.samples,
                    human(d.took),
                    d.quality,
                    human(d.since_save)
                )
            }
        })
    }
}

/// Sees every [`Report`] of a [`Watch`](super::Watch) before its
/// [`Watch::run`](super::Watch::run) callback does, with the film of a [`Report::Wrote`] (`None`
/// for the other reports). Runs on the render thread.
pub type Observer = Box<dyn FnMut(&Report, Option<&Film>) + Send>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reload_superseded_before_its_first_frame_says_which_file_changed() {
        let mut r = ReloadReport::started(4, vec![PathBuf::from("/d/scene.ron")], 16);
        let line = r.to_string();
        assert!(
            line.starts_with("reload 4: scene.ron changed | superseded")
                && !line.contains("no changes"),
            "{line}"
        );
        r.applied = true;
        r.changes.reordered = true;
        r.first_pass = Some((1, Duration::from_millis(9)));
        r.preview = true;
        let line = r.to_string();
        assert!(line.contains("entities reordered |"), "{line}");
        assert!(line.contains("first pass 9.00 ms (preview)"), "{line}");
    }
}
