//! `particles run --resume`: a run stopped part-way (at `--frames K`, or killed with SIGKILL)
//! and resumed from its last checkpoint writes the same frames (bit for bit) and the same
//! statistics (but for the wall-clock columns) as an uninterrupted run; checkpoints of
//! another scene or damaged ones are refused by name.

mod common;

use std::path::Path;
use std::process::Stdio;

use common::{error_lines, particles_ok, temp_dir, wait_until};

/// Small scenes of every solver kind with carried state: PBF (frame counter, reordering),
/// IISPH water (warm-started pressures), granular with upscaling (stresses, passive points).
const SCENES: [(&str, &str); 3] = [
    ("pbf", "kind = \"pbf\"\niterations = 3\nsubsteps = 2"),
    ("iisph", "kind = \"iisph\"\nsubsteps = 2"),
    (
        "granular",
        "kind = \"granular\"\nsubsteps = 2\nfriction_angle_deg = 30.0\nupscaling_factor = 2",
    ),
];

fn scene_text(solver: &str) -> String {
    scene_text_at(solver, 0.02)
}

fn scene_text_at(solver: &str, spacing: f64) -> String {
    format!(
        r#"name = "resume"
[simulation]
precision = "f32"
particle_spacing = {spacing}
duration = 0.48
frame_dt = 0.016
[solver]
{solver}
reorder_every = 3
[boundary]
model = "volume-map"
initial_masses = "calibrated"
[tank]
min = [0.0, 0.0, 0.0]
max = [0.3, 0.2, 0.08]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.12, 0.12, 0.08]
[output]
every_frames = 1
vtk = true
"#
    )
}

/// Where the commands run: the default volume-map cache (`target/cache/volume-maps` there)
/// stays out of the tree.
fn cwd() -> std::path::PathBuf {
    std::env::temp_dir()
}

fn run_ok(args: &[&str]) {
    particles_ok(args, &cwd());
}

/// The statistics without the wall-clock columns (those named `*_s` but `time_s` and
/// `max_speed_m_s`).
fn stats_without_clock(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("stats.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| matches!(header[i], "time_s" | "max_speed_m_s") || !header[i].ends_with("_s"))
        .collect();
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| f[i].to_string()).collect()
        })
        .collect()
}

fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "vtk"))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

/// The number of rows of the statistics file `stats` (0 before it exists).
fn rows(stats: &Path) -> usize {
    std::fs::read_to_string(stats)
        .map(|t| t.lines().count().saturating_sub(1))
        .unwrap_or(0)
}

/// Kills `particles run` with SIGKILL once its statistics hold `frames` rows; panics if the
/// run ended before (the scene is then too fast for the test to mean anything).
fn run_and_kill_after(args: &[&str], stats: &Path, frames: usize) -> usize {
    let mut child = common::particles(args, &cwd(), &[])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_until(
        &mut child,
        &format!("the run reaching frame {frames} to be killed there"),
        || rows(stats) >= frames,
    );
    child.kill().unwrap(); // SIGKILL on Unix
    child.wait().unwrap();
    rows(stats)
}

/// Asserts that the run in `b` wrote what the run in `a` wrote.
fn assert_same_outputs(name: &str, a: &Path, b: &Path) {
    assert_eq!(
        stats_without_clock(a),
        stats_without_clock(b),
        "{name}: statistics differ"
    );
    let (a, b) = (outputs(a), outputs(b));
    assert_eq!(a.len(), b.len(), "{name}: frame files differ in number");
    for ((fa, da), (fb, db)) in a.iter().zip(&b) {
        assert_eq!(fa, fb);
        assert!(da == db, "{name}: {fa} differs after resuming");
    }
}

#[test]
fn a_run_stopped_part_way_resumes_bit_for_bit() {
    for (name, solver) in SCENES {
        let dir = temp_dir("particles-resume", name);
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, scene_text(solver)).unwrap();
        let cache = dir.join("cache");
        let (scene_s, cache_s) = (scene.to_str().unwrap(), cache.to_str().unwrap());
        let (straight, resumed) = (dir.join("straight"), dir.join("resumed"));
        let run = |out: &Path, frames: &str, more: &[&str]| {
            let mut args = vec!["run", scene_s, "--cache", cache_s, "--frames", frames];
            args.extend(["--out", out.to_str().unwrap()]);
            args.extend(more);
            run_ok(&args);
        };
        run(&straight, "24", &[]);
        // Stops at frame 11 with checkpoints at 4, 8 and 11 (the end), then continues.
        run(&resumed, "11", &["--checkpoint-every", "4"]);
        run(&resumed, "24", &["--checkpoint-every", "4", "--resume"]);
        assert_same_outputs(name, &straight, &resumed);
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[test]
fn a_killed_run_resumes_bit_for_bit() {
    // The richest carried state: granular stresses, warm-started pressures, passive points.
    let (name, solver) = SCENES[2];
    let dir = temp_dir("particles-resume", "killed");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, scene_text_at(solver, 0.01)).unwrap();
    let cache = dir.join("cache");
    let (scene_s, cache_s) = (scene.to_str().unwrap(), cache.to_str().unwrap());
    let (straight, resumed) = (dir.join("straight"), dir.join("resumed"));
    let args = |out: &Path| {
        let o = out.to_str().unwrap().to_string();
        vec![
            "run".to_string(),
            scene_s.into(),
            "--cache".into(),
            cache_s.into(),
            "--frames".into(),
            "24".into(),
            "--checkpoint-every".into(),
            "4".into(),
            "--out".into(),
            o,
        ]
    };
    let straight_args = args(&straight);
    run_ok(&straight_args.iter().map(String::as_str).collect::<Vec<_>>());
    let killed_args = args(&resumed);
    let killed: Vec<&str> = killed_args.iter().map(String::as_str).collect();
    // Killed after frame 14 or later: its last checkpoint is at frame 12 (or later), and
    // frames after it were written and must be rewritten identically.
    let rows = run_and_kill_after(&killed, &resumed.join("stats.csv"), 14);
    assert!(rows < 24, "killed after {rows} frames");
    let mut again = killed.clone();
    again.push("--resume");
    run_ok(&again);
    assert_same_outputs(name, &straight, &resumed);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn foreign_damaged_and_missing_checkpoints_are_refused_by_name() {
    let dir = temp_dir("particles-resume", "refused");
    let (a, b) = (dir.join("a.toml"), dir.join("b.toml"));
    std::fs::write(&a, scene_text(SCENES[0].1)).unwrap();
    std::fs::write(&b, scene_text(SCENES[1].1)).unwrap();
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    let err = |args: &[&str]| {
        let o = common::run_particles(args, &cwd(), &[]);
        assert!(!o.status.success(), "{args:?} should fail");
        error_lines(&o, &dir, "TMP")
    };
    let a_s = a.to_str().unwrap();
    insta::assert_snapshot!(
        "missing",
        err(&["run", a_s, "--frames", "2", "--out", out_s, "--resume"])
    );
    run_ok(&[
        "run",
        a_s,
        "--frames",
        "2",
        "--checkpoint-every",
        "1",
        "--out",
        out_s,
    ]);
    let ck = out.join("checkpoint.sphck");
    let good = std::fs::read(&ck).unwrap();
    insta::assert_snapshot!(
        "another_scene",
        err(&[
            "run",
            b.to_str().unwrap(),
            "--frames",
            "3",
            "--out",
            out_s,
            "--resume"
        ])
    );
    std::fs::write(&ck, &good[..good.len() / 2]).unwrap();
    insta::assert_snapshot!(
        "truncated",
        err(&["run", a_s, "--frames", "3", "--out", out_s, "--resume"])
    );
    let mut flipped = good.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 1;
    std::fs::write(&ck, &flipped).unwrap();
    insta::assert_snapshot!(
        "corrupt",
        err(&["run", a_s, "--frames", "3", "--out", out_s, "--resume"])
    );
    std::fs::write(&ck, b"# vtk DataFile Version 4.2\n").unwrap();
    insta::assert_snapshot!(
        "foreign",
        err(&["run", a_s, "--frames", "3", "--out", out_s, "--resume"])
    );
    std::fs::remove_dir_all(&dir).ok();
}
