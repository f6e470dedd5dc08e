//! `rondo farm slurm`: the scheduler script of a split render.

use rondo::cli::print_line;
use std::path::Path;

use anyhow::{Context, Result, bail};

use super::args::RenderArgs;
use rondo::cli::check_output_file;

/// `rondo farm slurm`: prints the sbatch script; `job` carries the Slurm options.
pub fn slurm(
    scene: &Path,
    output: &Path,
    mut job: rondo::farm::SlurmJob,
    options: &RenderArgs,
) -> Result<()> {
    check_output_file(output)?;
    if options.threads.is_some() {
        bail!("--threads: each task renders with --cpus-per-task threads");
    }
    let loaded =
        rondo::scene::load::load_scene(scene, &mut rondo::scene::assets::AssetCache::default())?;
    let mut settings = loaded.settings;
    options
        .overrides()
        .apply(&mut settings)
        .map_err(|m| anyhow::anyhow!("{}: {m}", scene.display()))?;
    job.rondo = std::env::current_exe().context("locating the rondo binary")?;
    job.scene = std::path::absolute(scene)?;
    job.output = std::path::absolute(output)?;
    job.spp = settings.spp;
    let mut overrides = options.overrides();
    overrides.spp = None;
    job.render_flags = rondo::farm::render_flags(&overrides, options.layout);
    let script = rondo::farm::slurm_script(&job)?;
    print_line(script.trim_end_matches('\n'))?;
    eprintln!(
        "{} tasks, {} spp; partials in {}; submit with `sbatch <this script>`",
        job.tasks,
        job.spp,
        rondo::farm::parts_dir(&job.output).display()
    );
    Ok(())
}
