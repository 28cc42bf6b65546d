//! What `particles` says about bad output directories and unreadable frames, and that a
//! rerun into the same directory leaves no stale frames and keeps the statistics of every
//! finished frame.

mod common;

use std::path::Path;

use common::{error_lines, particles_ok, run_particles, temp_dir};

const SCENE: &str = r#"name = "errors"
[simulation]
precision = "f32"
particle_spacing = 0.025
duration = 0.16
frame_dt = 0.016
[solver]
kind = "pbf"
substeps = 1
iterations = 2
[boundary]
model = "collision"
[tank]
min = [0.0, 0.0, 0.0]
max = [0.2, 0.2, 0.1]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.1]
[output]
every_frames = 1
vtk = true
"#;

/// The `error:` lines of a failing command (run in `tmp`), with `tmp` written `TMP`.
fn error_of(args: &[&str], tmp: &Path) -> String {
    let o = run_particles(args, tmp, &[]);
    assert!(!o.status.success(), "{args:?} should fail");
    error_lines(&o, tmp, "TMP")
}

#[test]
fn unwritable_output_and_corrupt_frames_are_named() {
    let dir = temp_dir("particles-errors", "named");
    let scene = dir.join("s.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let s = scene.to_str().unwrap();
    insta::assert_snapshot!(
        "out_under_proc",
        error_of(
            &["run", s, "--frames", "1", "--out", "/proc/particles-test/x"],
            &dir
        )
    );
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    particles_ok(["run", s, "--frames", "2", "--out", out_s], &dir);
    let frame = out.join("frame_00001.vtk");
    let bytes = std::fs::read(&frame).unwrap();
    std::fs::write(&frame, &bytes[..bytes.len() / 2]).unwrap();
    insta::assert_snapshot!("truncated_frame", error_of(&["render", out_s], &dir));
    std::fs::write(&frame, "not a frame").unwrap();
    insta::assert_snapshot!("foreign_frame", error_of(&["render", out_s], &dir));
    insta::assert_snapshot!(
        "repose_without_run",
        error_of(&["repose", dir.to_str().unwrap()], &dir)
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_shorter_rerun_leaves_no_stale_frames() {
    let dir = temp_dir("particles-errors", "rerun");
    let scene = dir.join("s.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let (s, out) = (scene.to_str().unwrap(), dir.join("out"));
    let out_s = out.to_str().unwrap();
    particles_ok(["run", s, "--frames", "6", "--out", out_s], &dir);
    particles_ok(["run", s, "--frames", "3", "--out", out_s], &dir);
    let mut frames: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("frame_"))
        .collect();
    frames.sort();
    assert_eq!(
        frames,
        [
            "frame_00000.vtk",
            "frame_00001.vtk",
            "frame_00002.vtk",
            "frame_00003.vtk"
        ]
    );
    let stats = std::fs::read_to_string(out.join("stats.csv")).unwrap();
    assert_eq!(stats.lines().count(), 1 + 3, "{stats}");
    std::fs::remove_dir_all(&dir).ok();
}
