//! `rondo check`: a scene's load errors and warnings.

use rondo::cli::print_line;
use std::path::Path;

use anyhow::Result;

/// `rondo check`: one line per warning on stdout, then a count; load errors go to `main`.
pub fn run(scene: &Path) -> Result<()> {
    let loaded =
        rondo::scene::load::load_scene(scene, &mut rondo::scene::assets::AssetCache::default())?;
    let warnings = rondo::scene::check::check_scene(&loaded);
    for w in &loaded.warnings {
        print_line(format_args!("warning: {w}"))?;
    }
    for w in &warnings {
        print_line(format_args!("warning: {w}"))?;
    }
    match warnings.len() + loaded.warnings.len() {
        0 => print_line(format_args!("{}: no warnings", scene.display()))?,
        1 => print_line(format_args!("{}: 1 warning", scene.display()))?,
        n => print_line(format_args!("{}: {n} warnings", scene.display()))?,
    }
    Ok(())
}
