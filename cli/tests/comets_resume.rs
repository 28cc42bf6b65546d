//! `particles comets`: a population study killed with SIGKILL at a random moment and started
//! again with the same command writes the same files, byte for byte (snapshots, final table,
//! checkpoint), as an uninterrupted run ("kill -9 at a random moment, rerun the
//! same command: identical output files").

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime};

const BIN: &str = env!("CARGO_BIN_EXE_particles");

/// The shipped scattered-disk population (its 1000 comets), over a span long enough to be
/// killed part-way, with a checkpoint every 50 years.
fn spec_text() -> String {
    let shipped = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../populations/scattered-disk.toml"),
    )
    .unwrap();
    let csv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../populations/scattered-disk.csv");
    let text = shipped
        .replace(
            "file = \"scattered-disk.csv\"",
            &format!("file = {:?}", csv.canonicalize().unwrap()),
        )
        .replace("years = 10000.0", "years = 6000.0")
        .replace(
            "snapshot_every_years = 1000.0",
            "snapshot_every_years = 600.0\ncheckpoint_every_years = 50.0",
        );
    assert!(text.contains("years = 6000.0") && text.contains("checkpoint_every_years"));
    text
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("particles-comets-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn comets(spec: &Path, out: &Path) -> Command {
    let mut c = Command::new(BIN);
    c.arg("comets")
        .arg(spec)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    c
}

/// Every file under `dir` (relative name, bytes), sorted.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let name = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.push((name, std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// A pseudo-random fraction in [0.05, 0.95) from the clock (printed, so that a failure can be
/// replayed by hand with the same delay).
fn random_fraction() -> f64 {
    let nanos = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .unwrap()
        .subsec_nanos();
    let mixed = u64::from(nanos).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11;
    0.05 + 0.9 * (mixed as f64 / (1u64 << 53) as f64)
}

#[test]
fn a_killed_population_study_resumes_to_identical_files() {
    let dir = temp_dir("killed");
    let spec = dir.join("population.toml");
    std::fs::write(&spec, spec_text()).unwrap();
    let (straight, resumed) = (dir.join("straight"), dir.join("resumed"));

    let t0 = Instant::now();
    assert!(comets(&spec, &straight).status().unwrap().success());
    let straight_time = t0.elapsed();

    // Kill at a random moment of the run (after its first checkpoint, so that something is
    // resumed); if the run ends first, try again with a shorter delay.
    let mut killed = false;
    for attempt in 0..6 {
        let fraction = random_fraction() / f64::from(1u32 << attempt);
        eprintln!("attempt {attempt}: SIGKILL {fraction:.3} of the straight run's {straight_time:?} after the first checkpoint");
        let mut child = comets(&spec, &resumed).spawn().unwrap();
        let start = Instant::now();
        while !resumed.join("checkpoint.json").exists() && child.try_wait().unwrap().is_none() {
            assert!(
                start.elapsed() < Duration::from_secs(300),
                "no checkpoint written"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
        std::thread::sleep(straight_time.mul_f64(fraction));
        if child.try_wait().unwrap().is_none() {
            child.kill().unwrap(); // SIGKILL on Unix
            child.wait().unwrap();
            killed = !resumed.join("final.parquet").exists();
            if killed {
                break;
            }
        } else {
            std::fs::remove_dir_all(&resumed).unwrap();
        }
    }
    assert!(killed, "the study always ended before it could be killed");
    // A kill between an atomic write's link and its rename leaves `.<name>.<6 characters>`
    // behind (it happened in CI); plant such leftovers so that their removal on resume is
    // checked every time, not only when the kill lands in that window.
    std::fs::write(resumed.join(".checkpoint.json.Stale1"), b"{").unwrap();
    std::fs::create_dir_all(resumed.join("snapshots")).unwrap();
    std::fs::write(
        resumed.join("snapshots/.snapshot_000003.parquet.Stale2"),
        b"PAR1",
    )
    .unwrap();

    assert!(comets(&spec, &resumed).status().unwrap().success());
    let (a, b) = (files(&straight), files(&resumed));
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b), "the resumed study wrote other files");
    assert!(a.iter().any(|f| f.0.ends_with("final.parquet")) && a.len() >= 12);
    for ((name, da), (_, db)) in a.iter().zip(&b) {
        assert!(da == db, "{name} differs after the kill and the rerun");
    }
    std::fs::remove_dir_all(&dir).ok();
}
