//! The messages of `particles run` for arguments a user can get wrong (what `cargo xtask
//! run` passes on), as reviewed snapshots (`tests/snapshots/cli_errors__<case>.snap`).
//! Each case runs the binary in a fresh directory holding a valid scene (`good.toml` with
//! `cube.obj`), a malformed one (`bad.toml`) and a plain file (`notes.txt`); every case must
//! fail before simulating anything, with exit code 1 or 2 and the message on stderr (the
//! directory reads `<dir>`). Review new snapshots as described in
//! `crates/sph-scene/tests/error_snapshots.rs`.

use std::path::{Path, PathBuf};
use std::process::Command;

const GOOD: &str = r#"
name = "good"
[simulation]
particle_spacing = 0.05
duration = 0.1
frame_dt = 0.02
[solver]
kind = "pbf"
substeps = 2
iterations = 2
[tank]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.2, 0.2, 0.2]
[output]
vtk = false
"#;

/// A fresh directory with the files the cases use.
fn case_dir(case: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("particles-cli-{}-{case}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("good.toml"), GOOD).unwrap();
    std::fs::write(
        dir.join("bad.toml"),
        GOOD.replace("frame_dt = 0.02", "frame_dt = 1e30"),
    )
    .unwrap();
    std::fs::write(dir.join("notes.txt"), "not a directory\n").unwrap();
    dir
}

/// Runs `particles ARGS` in `dir`; returns (exit code, stderr with `dir` as `<dir>`).
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_particles"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .env_remove("CLICOLOR_FORCE")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr)
        .replace(&dir.display().to_string(), "<dir>")
        .trim_end()
        .to_string();
    (out.status.code().unwrap_or(-1), stderr)
}

#[test]
fn command_line_error_messages() {
    let cases: &[(&str, &[&str])] = &[
        ("scene_without_path", &["run"]),
        ("scene_frames_zero", &["run", "good.toml", "--frames", "0"]),
        (
            "scene_frames_negative",
            &["run", "good.toml", "--frames", "-3"],
        ),
        (
            "scene_frames_not_a_number",
            &["run", "good.toml", "--frames", "many"],
        ),
        (
            "scene_out_is_a_file",
            &["run", "good.toml", "--quick", "--out", "notes.txt"],
        ),
        ("scene_missing_file", &["run", "absent.toml"]),
        ("scene_path_is_a_directory", &["run", "."]),
        ("scene_malformed", &["run", "bad.toml"]),
        ("scene_not_toml", &["run", "notes.txt"]),
        ("unknown_command", &["rnu"]),
    ];
    for (name, args) in cases {
        let dir = case_dir(name);
        let (code, stderr) = run(&dir, args);
        assert!(
            code == 1 || code == 2,
            "{name}: exit code {code}, stderr:\n{stderr}"
        );
        insta::assert_snapshot!(*name, stderr);
        // Nothing was simulated: no output directory appeared.
        assert!(!dir.join("target").exists(), "{name}: wrote output");
    }
}

/// A run whose frame files cannot fit on the disk is refused after its first frame file,
/// naming both sizes, instead of running until the disk is full: 62,500 particles (2.75 MB a
/// frame) over the 10⁷ frames the scene format allows is 27.5 TB.
#[test]
fn frame_files_that_cannot_fit_on_the_disk_are_refused() {
    let dir = case_dir("output_volume");
    let scene = GOOD
        .replace("particle_spacing = 0.05", "particle_spacing = 0.02")
        .replace("duration = 0.1", "duration = 2e5")
        .replace("max = [0.2, 0.2, 0.2]", "max = [1.0, 0.5, 1.0]")
        .replace("vtk = false", "vtk = true");
    std::fs::write(dir.join("big.toml"), scene).unwrap();
    let (code, stderr) = run(&dir, &["run", "big.toml", "--out", "out"]);
    assert_eq!(code, 1, "{stderr}");
    let error = stderr
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or("");
    assert!(
        error.contains("writing 10000000 more frame files (output.every_frames = 1, about 2.")
            && error.contains("TB but out has only")
            && error.contains("free"),
        "{stderr}"
    );
    assert!(dir.join("out/frame_00000.vtk").is_file());
    assert!(!dir.join("out/frame_00001.vtk").exists(), "the run went on");
    std::fs::remove_dir_all(&dir).ok();
}
