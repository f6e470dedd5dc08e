//! Runtime CPU dispatch: the render loop's x86-64-v3 copy and its baseline copy compute the same
//! image, bit for bit, for every shipped scene, every layout and both samplers. On a CPU without
//! x86-64-v3 both runs take the baseline copy and the comparison says nothing; the test then
//! says so on stderr.

mod common;

use std::path::Path;
use std::process::Command;

use common::{scenes_dir, temp_dir};
use rondo::cpu::Isa;

/// Renders `scene` to `out` with `extra` arguments; `baseline` forces the baseline copy.
fn render(scene: &Path, out: &Path, extra: &[&str], baseline: bool) -> Vec<u8> {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rondo"));
    cmd.arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--width", "40", "--height", "32", "--spp", "4"])
        .args(extra);
    if baseline {
        cmd.env("RONDO_CPU", "baseline");
    } else {
        cmd.env_remove("RONDO_CPU");
    }
    let run = cmd.output().expect("start rondo");
    assert!(
        run.status.success(),
        "{}: {}",
        scene.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    std::fs::read(out).expect("read the image")
}

#[test]
fn both_copies_of_the_render_loop_render_the_same_bits() {
    if Isa::detect() == Isa::BASELINE {
        eprintln!("this CPU has no x86-64-v3: both runs use the baseline copy");
    }
    let dir = temp_dir("cpu-dispatch");
    let mut scenes: Vec<_> = std::fs::read_dir(scenes_dir())
        .expect("scenes/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 10, "{scenes:?}");
    let mut runs: Vec<(&Path, Vec<&str>)> = scenes
        .iter()
        .map(|s| (s.as_path(), vec!["--sampler", "sobol"]))
        .collect();
    let cornell = scenes_dir().join("cornell.ron");
    for layout in ["aos", "soa", "soa-simd", "hybrid"] {
        runs.push((
            &cornell,
            vec!["--layout", layout, "--sampler", "independent"],
        ));
    }
    for (k, (scene, extra)) in runs.iter().enumerate() {
        let out = dir.join(format!("{k}.exr"));
        let dispatched = render(scene, &out, extra, false);
        let baseline = render(scene, &out, extra, true);
        assert!(
            dispatched == baseline,
            "{} {extra:?}: the x86-64-v3 copy renders other bits than the baseline copy",
            scene.display()
        );
    }
}
