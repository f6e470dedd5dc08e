//! An asset file is read again only when a change is reported for it or its
//! metadata changed (when the caller reports changes), and once per load otherwise. Counted in
//! bytes read ([`AssetCache::bytes_read`]), never timed.

mod common;

use std::path::{Path, PathBuf};

use rondo::scene::assets::AssetCache;

/// A one-triangle OBJ whose first vertex has x = `x` (one digit: the same size for every `x`).
fn triangle(x: u8) -> String {
    format!("v {x} 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
}

fn size(path: &Path) -> u64 {
    std::fs::metadata(path).expect("stat").len()
}

/// The first vertex's x of the mesh at `path`, as the cache gives it.
fn first_x(cache: &mut AssetCache, path: &Path) -> f32 {
    cache.begin_load();
    let mesh = cache.mesh(path).expect("mesh");
    mesh.positions[0].x
}

/// A cache that trusts unreported files, with `mesh.obj` loaded once.
fn watched(dir: &Path) -> (AssetCache, PathBuf) {
    let mesh = dir.join("mesh.obj");
    std::fs::write(&mesh, triangle(1)).expect("write mesh");
    let mut cache = AssetCache::default();
    cache.set_reported_changes(true);
    assert_eq!(first_x(&mut cache, &mesh), 1.0);
    assert_eq!(cache.bytes_read(), size(&mesh));
    (cache, mesh)
}

#[test]
fn without_reported_changes_every_load_reads_each_file_once() {
    let dir = common::temp_dir("asset-reads-plain");
    let mesh = dir.join("mesh.obj");
    std::fs::write(&mesh, triangle(1)).expect("write mesh");
    let mut cache = AssetCache::default();
    for load in 1..=3 {
        cache.begin_load();
        cache.mesh(&mesh).expect("mesh");
        cache.mesh(&mesh).expect("mesh asked for twice");
        assert_eq!(cache.bytes_read(), load * size(&mesh));
    }
}

#[test]
fn an_unreported_file_with_unchanged_metadata_is_not_read_again() {
    let dir = common::temp_dir("asset-reads-trusted");
    let (mut cache, mesh) = watched(&dir);
    let read = cache.bytes_read();
    assert_eq!(first_x(&mut cache, &mesh), 1.0);
    assert_eq!(cache.bytes_read(), read, "an untouched file costs nothing");
}

#[test]
fn a_reported_file_is_read_again_even_with_the_same_size_and_mtime() {
    let dir = common::temp_dir("asset-reads-reported");
    let (mut cache, mesh) = watched(&dir);
    let stamp = common::watch_diff::stamp(&mesh).1;
    std::fs::write(&mesh, triangle(2)).expect("rewrite mesh");
    common::watch_diff::set_mtime(&mesh, stamp);
    let read = cache.bytes_read();
    // Reported under its canonical path, as the watcher names it.
    cache.invalidate(&[mesh.canonicalize().expect("canonical")]);
    assert_eq!(first_x(&mut cache, &mesh), 2.0);
    assert_eq!(cache.bytes_read() - read, size(&mesh));
}

#[test]
fn an_unreported_change_of_metadata_is_read_again() {
    let dir = common::temp_dir("asset-reads-metadata");
    let (mut cache, mesh) = watched(&dir);
    // No event (a platform without reliable ones): a longer file.
    std::fs::write(&mesh, format!("{}# more\n", triangle(3))).expect("rewrite mesh");
    let read = cache.bytes_read();
    assert_eq!(first_x(&mut cache, &mesh), 3.0);
    assert_eq!(cache.bytes_read() - read, size(&mesh));
    // A file replaced by another of the same size and mtime (another inode).
    let stamp = common::watch_diff::stamp(&mesh).1;
    let other = dir.join("other.obj");
    std::fs::write(&other, format!("{}# more\n", triangle(4))).expect("write other");
    common::watch_diff::set_mtime(&other, stamp);
    std::fs::rename(&other, &mesh).expect("rename over the mesh");
    let read = cache.bytes_read();
    assert_eq!(first_x(&mut cache, &mesh), 4.0);
    assert_eq!(cache.bytes_read() - read, size(&mesh));
}

#[test]
fn a_change_reported_for_a_symlinks_target_or_a_directory_reads_the_link_again() {
    let dir = common::temp_dir("asset-reads-symlink");
    std::fs::create_dir(dir.join("real")).expect("mkdir");
    std::fs::create_dir(dir.join("scene")).expect("mkdir");
    let target = dir.join("real/mesh.obj");
    std::fs::write(&target, triangle(1)).expect("write mesh");
    let link = dir.join("scene/mesh.obj");
    std::os::unix::fs::symlink("../real/mesh.obj", &link).expect("symlink");
    let mut cache = AssetCache::default();
    cache.set_reported_changes(true);
    assert_eq!(first_x(&mut cache, &link), 1.0);

    let canonical = target.canonicalize().expect("canonical");
    let read = cache.bytes_read();
    cache.invalidate(std::slice::from_ref(&canonical));
    assert_eq!(first_x(&mut cache, &link), 1.0);
    assert_eq!(cache.bytes_read() - read, size(&target), "target named");

    let read = cache.bytes_read();
    cache.invalidate(&[canonical.parent().expect("directory").to_path_buf()]);
    assert_eq!(first_x(&mut cache, &link), 1.0);
    assert_eq!(cache.bytes_read() - read, size(&target), "directory named");

    // A sibling directory whose name extends the target's is not above it.
    let read = cache.bytes_read();
    cache.invalidate(&[dir.canonicalize().expect("canonical").join("rea")]);
    cache.invalidate(&[dir.canonicalize().expect("canonical").join("real2")]);
    assert_eq!(first_x(&mut cache, &link), 1.0);
    assert_eq!(cache.bytes_read(), read);
}
