//! Reloading: due changes become a load of the scene (the renderer reads again only the files
//! events named and parses again only the entities an edit touched), the files the load read
//! become the watched set, and a good load starts a new [`Job`]; a failed one keeps the last
//! good scene rendering and is reported once it stands.

use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Instant;

use super::files::watch_key;
use super::job::Job;
use super::options::Denoising;
use super::pending::{Failure, Pending};
use super::report::{ReloadReport, Report};
use super::{Reporter, Watch};
use crate::app::AssetWork;

impl Watch {
    /// Acts on due changes: reports a failure that stood, or loads. A failed load is kept
    /// pending, to be reported three windows later unless another event comes first.
    pub(super) fn act(&mut self, mut p: Pending, out: &mut Reporter<'_>) -> Option<Pending> {
        if let Some((failure, _)) = p.failed.take() {
            match failure {
                Failure::Missing => {
                    if !std::mem::replace(&mut self.missing, true) {
                        let path = self.options.scene.clone();
                        out.emit(Report::SceneMissing { path }, None);
                    }
                }
                Failure::Error(error) => {
                    self.last_error = Some(error.to_string());
                    out.emit(Report::Failed(error), None);
                }
            }
            return None;
        }
        match self.reload(&p, out) {
            Ok(()) => None,
            Err(failure) => {
                let message = match &failure {
                    Failure::Missing => format!("{}: missing", self.options.scene.display()),
                    Failure::Error(e) => e.to_string(),
                };
                out.emit(Report::Deferred { message }, None);
                p.failed = Some((failure, Instant::now() + 3 * self.options.debounce));
                Some(p)
            }
        }
    }

    /// Watches `files`; returns whether anything new is watched (see [`FileWatcher::set_files`]).
    fn watch_files(&mut self, files: &[PathBuf], out: &mut Reporter<'_>) -> bool {
        let (dirs, count) = (self.watcher.directories(), self.watcher.file_count());
        let (added, warnings) = self.watcher.set_files(files);
        for message in warnings {
            out.emit(Report::Warning { message }, None);
        }
        if self.watcher.directories() != dirs || self.watcher.file_count() != count {
            out.emit(self.watching_report(), None);
        }
        added
    }

    /// The dependencies of a load to watch: all but the output image (which we write).
    fn dependencies(&mut self, dependencies: Vec<PathBuf>, out: &mut Reporter<'_>) -> Vec<PathBuf> {
        let mut files = Vec::with_capacity(dependencies.len());
        for dep in dependencies {
            let is_output = self.output_key.is_some()
                && watch_key(&dep).ok().map(|(_, k)| k) == self.output_key;
            if !is_output {
                files.push(dep);
            } else if !std::mem::replace(&mut self.warned_output, true) {
                let message = format!(
                    "{}: the output image is also a texture of the scene; its writes do not trigger reloads",
                    dep.display()
                );
                out.emit(Report::Warning { message }, None);
            }
        }
        files
    }

    /// Loads the scene after a change. On success the new scene is queued and a new job starts;
    /// on failure the old scene keeps rendering (if it was not finished), the image on disk is
    /// left alone, and the files the failed load asked for are watched too.
    pub(super) fn reload(&mut self, p: &Pending, out: &mut Reporter<'_>) -> Result<(), Failure> {
        // The pass this change interrupted is gone; the next one must run.
        self.cancel.store(false, Ordering::SeqCst);
        let scene = self.options.scene.clone();
        // The cache reads again only the files named by events (all of them if events were lost)
        // or whose metadata changed.
        if p.overflow {
            self.renderer.invalidate_all();
        } else {
            self.renderer.invalidate(&p.paths);
        }
        // Read again at once if the load made us watch something new (a directory, or a file the
        // last load did not read): a change to it between the read and the watch would go
        // unnoticed, as its events were dropped until then.
        let mut retried = false;
        // What every load of this reload read, the one retried included.
        let mut assets = AssetWork::default();
        let (info, parse) = loop {
            if matches!(std::fs::metadata(&scene), Err(e) if e.kind() == std::io::ErrorKind::NotFound)
            {
                return Err(Failure::Missing);
            }
            self.missing = false;
            let start = Instant::now();
            let result = self.renderer.load(&scene);
            let parse = start.elapsed();
            let info = match result {
                Ok(info) => {
                    assets += info.assets;
                    info
                }
                Err(e) => {
                    let mut files = self.good_files.clone();
                    files.extend(self.renderer.requested());
                    let files = self.dependencies(files, out);
                    if self.watch_files(&files, out) && !std::mem::replace(&mut retried, true) {
                        // Events for the newly watched files were dropped until now.
                        self.renderer.invalidate_all();
                        continue;
                    }
                    return Err(Failure::Error(Box::new(e)));
                }
            };
            let files = self.dependencies(info.dependencies.clone(), out);
            self.good_files = files.clone();
            if self.watch_files(&files, out) && !std::mem::replace(&mut retried, true) {
                self.renderer.invalidate_all();
                continue;
            }
            break (info, parse);
        };
        self.last_error = None;
        for message in &info.warnings {
            out.emit(
                Report::Warning {
                    message: message.clone(),
                },
                None,
            );
        }
        self.denoising = match self.options.denoise.or(info.settings.denoise) {
            Some(false) => Denoising::Off,
            Some(true) => Denoising::Output,
            None => Denoising::Off,
        };
        self.renderer.set_features(self.denoising != Denoising::Off);
        if let Some(worker) = &self.denoiser {
            worker.cancel();
        }

        if let Some(old) = self.job.take() {
            out.emit(Report::Rendered(old.report), None);
        }
        let number = self.reloads;
        self.reloads += 1;
        out.emit(
            Report::Started {
                reload: number,
                trigger: p.paths.clone(),
                spp: info.settings.spp,
                saved: p.last,
            },
            None,
        );
        self.job = Some(Job {
            report: ReloadReport {
                textures_decoded: assets.textures_decoded,
                environments_built: assets.environments_built,
                asset_bytes_read: assets.bytes_read,
                parse,
                counters: self.renderer.counters(),
                ..ReloadReport::started(number, p.paths.clone(), info.settings.spp)
            },
            saved: p.last,
        });
        Ok(())
    }
}
