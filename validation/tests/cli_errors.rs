//! The messages of the `validation` command line for arguments a user can get wrong
//! (`validation run ...`, what `cargo xtask validate` passes on; the scene commands are
//! `particles`', tested in `cli/tests/cli_errors.rs`), as reviewed snapshots (`tests/snapshots/cli_errors__<case>.snap`).
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
    let dir = std::env::temp_dir().join(format!("validation-cli-{}-{case}", std::process::id()));
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

/// Runs `validation ARGS` in `dir`; returns (exit code, stderr with `dir` as `<dir>`).
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_validation"))
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
        ("run_out_is_a_file", &["run", "--out", "notes.txt"]),
        ("run_only_without_id", &["run", "--only"]),
        ("run_unknown_flag", &["run", "--fast"]),
        ("unknown_command", &["valdiate"]),
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

/// An unknown experiment id names the ids it knows; their list changes as experiments are
/// added, so the snapshot shows it as `<ids>` and the test checks that it is not empty.
#[test]
fn unknown_experiment_id() {
    let dir = case_dir("unknown_id");
    let out = dir.join("out");
    let (code, stderr) = run(&dir, &["run", "--only", "no-such-id", "--out", "out"]);
    assert_eq!(code, 1, "{stderr}");
    let (head, known) = stderr
        .split_once("(known: ")
        .unwrap_or_else(|| panic!("no list of known ids in: {stderr}"));
    assert!(known.len() > 2, "{stderr}");
    insta::assert_snapshot!("run_unknown_experiment_id", format!("{head}(known: <ids>)"));
    assert!(!out.join("summary.json").exists());
}
