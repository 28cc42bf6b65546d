//! `particles comets` refuses, before integrating or writing anything, the inputs that used
//! to hang it or fill the disk and memory: a device or a named pipe as the specification or
//! the particle file, a snapshot cadence of thousands of files, a planet step far too short.

mod common;

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::{temp_dir, wait_bounded, wait_until, HANG};

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
    let dir = temp_dir("particles-comets-errors", case);
    std::fs::write(dir.join("spec.toml"), spec).unwrap();
    std::fs::write(dir.join("p.csv"), ROWS).unwrap();
    dir
}

/// Starts `particles comets SPEC --out DIR/out` in `dir`, its stderr piped.
fn start(dir: &Path, spec: &Path) -> std::process::Child {
    let out = dir.join("out");
    let args = [
        OsStr::new("comets"),
        spec.as_os_str(),
        OsStr::new("--out"),
        out.as_os_str(),
    ];
    common::particles(args, dir, &[])
        .stdout(Stdio::null())
        .spawn()
        .unwrap()
}

/// Runs `particles comets SPEC --out DIR/out` (bounded: these inputs used to hang it);
/// returns stderr and checks that it failed with nothing written.
fn refused(dir: &Path, spec: &Path) -> String {
    let what = format!("particles comets {}", spec.display());
    let out = wait_bounded(start(dir, spec), HANG, &what);
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
    let mut child = start(&dir, &dir.join("spec.toml"));
    // The handshake (no sleep): the Ctrl-C handler is installed before the study starts,
    // and the study's first loop writes `checkpoint.json` (atomically, after its snapshot 0)
    // before the long integration; nothing is printed before (the progress bar is hidden
    // when stderr is not a terminal). Once the file exists, SIGINT lands on the handler.
    let checkpoint = dir.join("out").join("checkpoint.json");
    wait_until(&mut child, "the study's first checkpoint", || {
        checkpoint.is_file()
    });
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    // How fast it stops is not asserted (a loaded machine may be slow); a stop that never
    // comes is a hang, bounded.
    let out = wait_bounded(child, HANG, "particles comets after Ctrl-C");
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{e}");
    assert!(
        e.contains("interrupted (Ctrl-C)") && e.contains("run the same command again"),
        "{e}"
    );
    assert!(checkpoint.is_file());
}
