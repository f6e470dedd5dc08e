//! `rondo check`: a scene's load errors and warnings.

use std::path::Path;

use anyhow::Result;

/// `rondo check`: one line per warning on stdout, then a count; load errors go to `main`.
pub fn run(scene: &Path) -> Result<()> {
    let loaded =
        rondo::scene::load::load_scene(scene, &mut rondo::scene::assets::AssetCache::default())?;
    let warnings = rondo::scene::check::check_scene(&loaded);
    for w in &loaded.warnings {
        println!("warning: {w}");
    }
    for w in &warnings {
        println!("warning: {w}");
    }
    match warnings.len() + loaded.warnings.len() {
        0 => println!("{}: no warnings", scene.display()),
        1 => println!("{}: 1 warning", scene.display()),
        n => println!("{}: {n} warnings", scene.display()),
    }
    Ok(())
}
