//! `particles comets` refuses, before integrating or writing anything, the inputs that used
//! to hang it or fill the disk and memory: a device or a named pipe as the specification or
//! the particle file, a snapshot cadence of thousands of files, a planet step far too short.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const SPEC: &str = r#"
[planets]
system = "outer_solar_system"
frame = "ecliptic_j2000"
scheme = "s6"
step_days = 730.5

[integrator]
variant = "barycentric"
scheme = "s2"
b1 = 0.21e-6
initial_step_days = 547.875

[particles]
file = "p.csv"
kind = "barycentric_elements"

[span]
years = 100.0
snapshot_every_years = 10.0
"#;

const ROWS: &str = "id,a,e,i,node,peri,mean_anomaly\n0,60.0,0.4,10.0,20.0,30.0,40.0\n";

fn case_dir(case: &str, spec: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("particles-comets-{}-{case}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("spec.toml"), spec).unwrap();
    std::fs::write(dir.join("p.csv"), ROWS).unwrap();
    dir
}

/// Starts `particles comets SPEC --out DIR/out`, its stderr piped.
fn start(dir: &Path, spec: &Path) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_particles"))
        .arg("comets")
        .arg(spec)
        .arg("--out")
        .arg(dir.join("out"))
        .env("NO_COLOR", "1")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

/// Runs `particles comets SPEC --out DIR/out` with a time bound; returns stderr and checks
/// that it failed with nothing written.
fn refused(dir: &Path, spec: &Path) -> String {
    let mut child = start(dir, spec);
    let started = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > Duration::from_secs(20) {
            child.kill().ok();
            panic!("{}: still running after 20 s", spec.display());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    assert!(!out.status.success());
    assert!(!dir.join("out").exists(), "output written");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn devices_and_pipes_are_refused_at_once() {
    let dir = case_dir("devices", SPEC);
    let e = refused(&dir, Path::new("/dev/zero"));
    assert!(e.contains("is a device, not a regular file"), "{e}");
    let particles_device = SPEC.replace("file = \"p.csv\"", "file = \"/dev/zero\"");
    std::fs::write(dir.join("dev.toml"), particles_device).unwrap();
    let e = refused(&dir, &dir.join("dev.toml"));
    assert!(e.contains("/dev/zero") && e.contains("is a device"), "{e}");
    let fifo = dir.join("fifo.toml");
    if Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        let e = refused(&dir, &fifo);
        assert!(e.contains("named pipe (FIFO)"), "{e}");
    }
}

#[test]
fn limits_are_named_with_their_key() {
    for (case, old, new, words) in [
        (
            "snapshots",
            "snapshot_every_years = 10.0",
            "snapshot_every_years = 1e-6",
            ["span.snapshot_every_years", "MAX_SNAPSHOTS"],
        ),
        (
            "planet_step",
            "step_days = 730.5",
            "step_days = 1e-6",
            ["planets.step_days", "MAX_STEP_GRID_BYTES"],
        ),
        (
            "first_step",
            "initial_step_days = 547.875",
            "initial_step_days = 1e-300",
            ["integrator.initial_step_days", "no progress"],
        ),
    ] {
        let dir = case_dir(case, &SPEC.replace(old, new));
        let e = refused(&dir, &dir.join("spec.toml"));
        assert!(words.iter().all(|w| e.contains(w)), "{case}: {e}");
    }
}

#[test]
fn ctrl_c_stops_with_the_state_saved() {
    // 64 comets over 10⁶ years: hours if not interrupted.
    let rows: String = std::iter::once("id,a,e,i,node,peri,mean_anomaly\n".to_string())
        .chain((0..64).map(|k| format!("{k},{},0.4,10.0,20.0,30.0,{}\n", 50.0 + k as f64, 5 * k)))
        .collect();
    let dir = case_dir(
        "ctrl_c",
        &SPEC
            .replace("years = 100.0", "years = 1e6")
            .replace("snapshot_every_years = 10.0", "snapshot_every_years = 1e3"),
    );
    std::fs::write(dir.join("p.csv"), rows).unwrap();
    let child = start(&dir, &dir.join("spec.toml"));
    std::thread::sleep(Duration::from_secs(2));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let stopping = Instant::now();
    let out = child.wait_with_output().unwrap();
    assert!(
        stopping.elapsed() < Duration::from_secs(10),
        "{:?} to stop",
        stopping.elapsed()
    );
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{e}");
    assert!(
        e.contains("interrupted (Ctrl-C)") && e.contains("run the same command again"),
        "{e}"
    );
    assert!(dir.join("out").join("checkpoint.json").is_file());
}
