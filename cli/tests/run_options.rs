//! `particles run --set KEY=VALUE` and `--until-rest` on the quick Bui column
//! (`scenes/granular_column_bui.toml`): an override reaches the run, is recorded, is taken
//! by `--resume` and refused when another is given; the rest criterion's samples and
//! verdict are written, and a run stopped and resumed writes the same samples, bit for bit,
//! as one whole run.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::{run_particles, stderr_of};

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .join("scenes")
        .join("granular_column_bui.toml")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = common::temp_dir("particles-options", name);
    std::fs::remove_dir_all(&d).ok(); // the runs create it: a fresh run starts without one
    d
}

/// `particles run` of the quick Bui column into `out` with `extra` arguments, one thread.
fn run(out: &Path, extra: &[&str]) -> Output {
    let scene = scene();
    let mut args = vec![
        "run".to_string(),
        scene.to_string_lossy().into_owned(),
        "--quick".into(),
        "--out".into(),
        out.to_string_lossy().into_owned(),
        "--no-cache".into(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    run_particles(&args, &std::env::temp_dir(), &[("RAYON_NUM_THREADS", "1")])
}

fn ok(o: &Output) -> String {
    let err = stderr_of(o);
    assert!(o.status.success(), "{err}");
    err
}

#[test]
fn an_override_is_checked_recorded_and_taken_by_resume() {
    let out = temp_dir("set");
    // Checked as the file is: an unknown key is refused with its path.
    let o = run(
        &out,
        &["--frames", "1", "--set", "solver.friction_angle_degs=25"],
    );
    let err = stderr_of(&o);
    assert!(!o.status.success());
    assert!(err.contains("friction_angle_degs"), "{err}");
    // Taken: the solver's friction angle moves the run.
    let set = ["--set", "solver.friction_angle_deg=25"];
    ok(&run(
        &out,
        &["--frames", "2", "--checkpoint-every", "1", set[0], set[1]],
    ));
    let source = std::fs::read_to_string(out.join("scene_source.txt")).unwrap();
    assert!(
        source.ends_with("quick\nset solver.friction_angle_deg=25\n"),
        "{source}"
    );
    let whole = std::fs::read(out.join("frame_00000.vtk")).unwrap();
    let stats = std::fs::read_to_string(out.join("stats.csv")).unwrap();
    // Another override on --resume is refused by name.
    let o = run(
        &out,
        &[
            "--frames",
            "3",
            "--resume",
            "--set",
            "solver.friction_angle_deg=30",
        ],
    );
    let err = stderr_of(&o);
    assert!(!o.status.success());
    assert!(err.contains("--set solver.friction_angle_deg=25"), "{err}");
    // None given: the recorded one is taken.
    ok(&run(&out, &["--frames", "3", "--resume"]));
    assert_eq!(std::fs::read(out.join("frame_00000.vtk")).unwrap(), whole);
    let resumed = std::fs::read_to_string(out.join("stats.csv")).unwrap();
    assert_eq!(resumed.lines().count(), stats.lines().count() + 1);
    // And the override changed the run: the default angle gives other frames.
    let plain = temp_dir("set-plain");
    ok(&run(&plain, &["--frames", "2", "--checkpoint-every", "0"]));
    let first_row = |s: &str| {
        s.lines()
            .nth(1)
            .unwrap()
            .split(',')
            .take(4)
            .collect::<Vec<_>>()
            .join(",")
    };
    let plain_stats = std::fs::read_to_string(plain.join("stats.csv")).unwrap();
    assert_ne!(first_row(&plain_stats), first_row(&stats));
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&plain).ok();
}

#[test]
fn until_rest_writes_its_samples_and_verdict_and_resumes_bit_for_bit() {
    let whole = temp_dir("rest-whole");
    let err = ok(&run(
        &whole,
        &["--frames", "3", "--checkpoint-every", "0", "--until-rest"],
    ));
    assert!(err.contains("rest: not at rest"), "{err}");
    let samples = std::fs::read_to_string(whole.join("rest_samples.csv")).unwrap();
    // The first state and one sample per frame.
    assert_eq!(samples.lines().count(), 1 + 4, "{samples}");
    let verdict = std::fs::read_to_string(whole.join("rest.json")).unwrap();
    assert!(verdict.contains("\"at_rest\": false"), "{verdict}");
    assert!(verdict.contains("\"speed_scale\": 0.05"), "{verdict}");
    // Stopped after frame 1 (its checkpoint), then resumed to frame 3.
    let split = temp_dir("rest-split");
    ok(&run(
        &split,
        &["--frames", "1", "--checkpoint-every", "1", "--until-rest"],
    ));
    ok(&run(&split, &["--frames", "3", "--resume", "--until-rest"]));
    let resumed = std::fs::read_to_string(split.join("rest_samples.csv")).unwrap();
    assert_eq!(resumed, samples);
    // A fresh run removes the earlier run's rest files.
    ok(&run(&split, &["--frames", "1", "--checkpoint-every", "0"]));
    assert!(!split.join("rest_samples.csv").exists());
    assert!(!split.join("rest.json").exists());
    std::fs::remove_dir_all(&whole).ok();
    std::fs::remove_dir_all(&split).ok();
}
