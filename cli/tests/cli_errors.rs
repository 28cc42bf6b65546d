//! The messages of `particles run` for arguments a user can get wrong (what `cargo xtask
//! run` passes on), as reviewed snapshots (`tests/snapshots/cli_errors__<case>.snap`).
//! Each case runs the binary in a fresh directory holding a valid scene (`good.toml`), a
//! malformed one (`bad.toml`) and a plain file (`notes.txt`); every case must fail before
//! simulating anything, with exit code 1 or 2 and the message on stderr (the directory
//! reads `<dir>`); the harness is `cli/tests/common/mod.rs`. Review new snapshots as described in
//! `crates/sph-scene/tests/error_snapshots.rs`.

mod common;

use common::{check_error_cases, error_case_dir, particles_bin, run_in, GOOD_SCENE};

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
    check_error_cases(particles_bin(), "particles-cli", cases, |name, stderr| {
        insta::assert_snapshot!(name, stderr);
    });
}

/// A run whose frame files cannot fit on the disk is refused after its first frame file,
/// naming both sizes, instead of running until the disk is full: 62,500 particles (2.75 MB a
/// frame) over the 10⁷ frames the scene format allows is 27.5 TB.
#[test]
fn frame_files_that_cannot_fit_on_the_disk_are_refused() {
    let dir = error_case_dir("particles-cli", "output_volume");
    let scene = GOOD_SCENE
        .replace("particle_spacing = 0.05", "particle_spacing = 0.02")
        .replace("duration = 0.1", "duration = 2e5")
        .replace("max = [0.2, 0.2, 0.2]", "max = [1.0, 0.5, 1.0]")
        .replace("vtk = false", "vtk = true");
    std::fs::write(dir.join("big.toml"), scene).unwrap();
    let (code, stderr) = run_in(particles_bin(), &dir, &["run", "big.toml", "--out", "out"]);
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
