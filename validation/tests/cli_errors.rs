//! The messages of the `validation` command line for arguments a user can get wrong
//! (`validation run ...`, what `cargo xtask validate` passes on; the scene commands are
//! `particles`', tested in `cli/tests/cli_errors.rs`), as reviewed snapshots (`tests/snapshots/cli_errors__<case>.snap`).
//! Each case runs the binary in a fresh directory holding a valid scene (`good.toml`), a
//! malformed one (`bad.toml`) and a plain file (`notes.txt`); every case must fail before
//! simulating anything, with exit code 1 or 2 and the message on stderr (the directory
//! reads `<dir>`); the harness is `cli/tests/common/mod.rs`. Review new snapshots as described in
//! `crates/sph-scene/tests/error_snapshots.rs`.

// The harness of the `particles` command-line tests, run here with the `validation` binary.
#[path = "../../cli/tests/common/mod.rs"]
mod common;

use common::{check_error_cases, error_case_dir, run_in};

const BIN: &str = env!("CARGO_BIN_EXE_validation");

#[test]
fn command_line_error_messages() {
    let cases: &[(&str, &[&str])] = &[
        ("run_out_is_a_file", &["run", "--out", "notes.txt"]),
        ("run_only_without_id", &["run", "--only"]),
        ("run_unknown_flag", &["run", "--fast"]),
        ("unknown_command", &["valdiate"]),
    ];
    check_error_cases(BIN, "validation-cli", cases, |name, stderr| {
        insta::assert_snapshot!(name, stderr);
    });
}

/// An unknown experiment id names the ids it knows; their list changes as experiments are
/// added, so the snapshot shows it as `<ids>` and the test checks that it is not empty.
#[test]
fn unknown_experiment_id() {
    let dir = error_case_dir("validation-cli", "unknown_id");
    let out = dir.join("out");
    let (code, stderr) = run_in(BIN, &dir, &["run", "--only", "no-such-id", "--out", "out"]);
    assert_eq!(code, 1, "{stderr}");
    let (head, known) = stderr
        .split_once("(known: ")
        .unwrap_or_else(|| panic!("no list of known ids in: {stderr}"));
    assert!(known.len() > 2, "{stderr}");
    insta::assert_snapshot!("run_unknown_experiment_id", format!("{head}(known: <ids>)"));
    assert!(!out.join("summary.json").exists());
}
