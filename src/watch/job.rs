//! The render of the current scene, one pass at a time: the scene applied on the first frame
//! (what it rebuilt goes into the [`ReloadReport`]), the image written whenever it improved,
//! each written pass handed to the denoise thread, until the film is complete or a newer save
//! replaces the job.

use std::path::Path;
use std::time::{Duration, Instant};

use super::options::Denoising;
use super::report::{ReloadReport, Report};
use super::{Reporter, Watch};
use crate::denoise::{DenoiseJob, DenoiseWorker, FilmImages, HIGH_QUALITY_FROM_SPP};
use crate::ecs::frame_log::BvhWork;
use crate::film::{Durability, write_output};

/// The samples of the image on disk for the current scene. After a cancelled pass the film
/// restarts from zero; images are written again only once they are better than this (passes are
/// deterministic, so fewer samples would only overwrite a better image).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct OnDisk {
    /// Samples per pixel.
    samples: u32,
    /// Whether it is real samples and not the preview (ordered after the preview of the same
    /// count: a 1-spp scene's real pass replaces its 1-sample preview).
    real: bool,
}

/// The render of the current scene, until it completes or a newer save replaces it.
pub(super) struct Job {
    pub(super) report: ReloadReport,
    /// When the save happened.
    pub(super) saved: Instant,
}

impl Watch {
    /// Hands the pass in the film to the denoise thread, if the scene denoises.
    fn denoise_pass(&mut self, reload: u64, saved: Instant) {
        if self.denoising == Denoising::Off {
            return;
        }
        let film = self.renderer.film();
        let quality = if film.samples < HIGH_QUALITY_FROM_SPP && !self.renderer.is_complete() {
            crate::denoise::Quality::Fast
        } else {
            crate::denoise::Quality::High
        };
        let job = DenoiseJob {
            reload,
            samples: film.samples,
            images: FilmImages::of(film),
            quality,
            write: match self.denoising {
                Denoising::Output => self.options.output.clone(),
                _ => None,
            },
            saved,
        };
        let sink = self.denoise_sink.clone();
        self.denoiser
            .get_or_insert_with(|| DenoiseWorker::start(sink))
            .submit(job);
    }

    /// Runs one frame of the current job: applies the scene if new, renders a pass, writes the
    /// image if it improved, and finishes the job when the film is complete.
    pub(super) fn step(&mut self, out: &mut Reporter<'_>) {
        let Some(job) = self.job.as_mut() else {
            return;
        };
        let start = Instant::now();
        let frame = self.renderer.run_once();
        let wall = start.elapsed();
        let r = &mut job.report;
        let first_frame = frame.applied.is_some();
        // The world holds a new scene or new geometry: the viewer's picking follows.
        let (picked, reload) = (first_frame || frame.geometry.is_some(), r.number);
        if let Some(changes) = frame.applied {
            r.applied = true;
            r.changes = changes;
            if !r.changes.is_empty() || r.number == 0 {
                // A new image; the one on disk is of another scene.
                self.on_disk = OnDisk::default();
            }
        }
        if let Some(g) = frame.geometry {
            match g.bvh {
                BvhWork::Built => r.bvh_rebuilt = true,
                BvhWork::Refitted => r.bvh_refit = true,
            }
            r.primitives = g.primitives;
            // The build that follows a refitted preview is not the reload's cost.
            if first_frame {
                r.bvh = g.took;
            }
        }
        r.materials_synced |= frame.materials;
        if first_frame {
            let pass = frame.pass.map_or(Duration::ZERO, |p| p.took);
            r.ecs = wall.saturating_sub(pass + r.bvh);
        }
        r.counters = self.renderer.counters();
        let complete = self.renderer.is_complete();
        if frame.pass.is_none() && !complete {
            // Cancelled: a change is on its way (or we are stopping). The film starts over.
            r.restarts += 1;
            return;
        }
        let mut denoise = None;
        if let Some(pass) = frame.pass {
            let film = self.renderer.film();
            let now = OnDisk {
                samples: pass.samples,
                real: !pass.preview,
            };
            if r.first_pass.is_none() {
                r.first_pass = Some((now.samples, pass.took));
                r.preview = pass.preview;
            }
            if now > self.on_disk {
                // No output file with `--serve` alone: the observer shows the image. A
                // denoised output is written by the denoise thread.
                let written = match self.options.output.as_deref() {
                    Some(o) if self.denoising != Denoising::Output => {
                        write_output(o, &film.image(), Durability::Live)
                    }
                    _ => Ok(()),
                };
                match written {
                    Ok(()) => {
                        let at = Instant::now();
                        let new_scene = self.on_disk == OnDisk::default();
                        self.on_disk = now;
                        r.samples = now.samples;
                        if r.first_image.is_none() {
                            r.first_image = Some(at.saturating_duration_since(job.saved));
                        }
                        let report = Report::Wrote {
                            reload: r.number,
                            samples: now.samples,
                            preview: !now.real,
                            spp: r.spp,
                            changes: r.changes.clone(),
                            new_scene,
                            at,
                        };
                        out.emit(report, Some(film));
                        if now.real {
                            denoise = Some((r.number, job.saved));
                        }
                    }
                    Err(e) => {
                        let output = self.options.output.as_deref().unwrap_or(Path::new(""));
                        let message = format!("{}: cannot write image: {e}", output.display());
                        out.emit(Report::Warning { message }, None);
                    }
                }
            }
        }
        if complete {
            // (Also when the reload changed nothing and the film was already complete.)
            r.samples = self.on_disk.samples;
            r.full = Some(job.saved.elapsed());
            if let Some(job) = self.job.take() {
                out.emit(Report::Rendered(job.report), None);
            }
        }
        if let Some((reload, saved)) = denoise {
            self.denoise_pass(reload, saved);
        }
        if picked {
            self.publish_pick(reload);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::Ordering;

    use super::super::WatchOptions;
    use super::super::pending::Pending;
    use super::*;

    #[test]
    fn a_reload_superseded_after_applying_its_change_makes_the_next_image_a_new_scene() {
        // The sequence of CI's browser failure: red, blue, then green applied by a reload whose
        // pass is cancelled by the next file event, and a reload of the same file that
        // therefore changes nothing itself. Its image is still of another scene than the last
        // one written (what the viewer's A/B keys on).
        let temp = tempfile::Builder::new()
            .prefix("rondo-watch-unit-")
            .tempdir()
            .expect("temp dir");
        let dir = temp.path();
        let scene = dir.join("scene.ron");
        let save = |colour: &str| {
            let text = format!(
                "Scene(camera: Camera(position: (0, 0, -5), look_at: (0, 0, 0), fov: 40.0),
                 settings: Settings(width: 8, height: 8, spp: 2, max_depth: 2),
                 materials: {{ \"wall\": Light(emit: Constant({colour}), intensity: 1.0) }},
                 entities: [Entity(material: \"wall\", shape: Sphere(center: (0, 0, 0), radius: 1))])"
            );
            std::fs::write(&scene, text).expect("write scene");
        };
        save("(1, 0, 0)");
        let mut w = Watch::new(WatchOptions::new(&scene, dir.join("out.png"))).expect("watch");
        let mut reports = Vec::new();
        let mut sink = |r: Report| reports.push(r);
        let mut out = Reporter {
            observer: None,
            report: &mut sink,
        };
        let render = |w: &mut Watch, out: &mut Reporter<'_>| {
            assert!(w.reload(&Pending::initial(), out).is_ok(), "loads");
            while w.job.is_some() {
                w.step(out);
            }
        };
        render(&mut w, &mut out);
        save("(0, 0, 1)");
        render(&mut w, &mut out);
        save("(0, 1, 0)");
        assert!(w.reload(&Pending::initial(), &mut out).is_ok(), "loads");
        w.cancel.store(true, Ordering::SeqCst);
        w.step(&mut out);
        render(&mut w, &mut out);
        drop(out);
        let firsts: Vec<(u64, bool, bool)> = reports
            .iter()
            .filter_map(|r| match r {
                Report::Wrote {
                    reload,
                    changes,
                    new_scene,
                    ..
                } => Some((*reload, changes.is_empty(), *new_scene)),
                _ => None,
            })
            .filter(|&(_, _, new_scene)| new_scene)
            .collect();
        assert_eq!(
            firsts,
            [(0, false, true), (1, false, true), (3, true, true)],
            "the first image of each scene, with whether its reload changed nothing"
        );
    }
}
