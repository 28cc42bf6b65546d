//! `particles comets`: a population study killed with SIGKILL at a random moment and started
//! again with the same command writes the same files, byte for byte (snapshots, final table,
//! checkpoint), as an uninterrupted run ("kill -9 at a random moment, rerun the
//! same command: identical output files").
//!
//! The moment of the kill comes from a seed, `COMETS_RESUME_SEED` (an integer; 41 when it is
//! not set, never the clock), printed at the start: a failing run is replayed with
//! `COMETS_RESUME_SEED=<seed> cargo test --release -p particles-cli --test comets_resume`,
//! and other moments are tried by setting other seeds. The seed fixes the moment as a
//! fraction of the straight run's time after the first checkpoint; where the process then
//! stands in its work still depends on the machine's speed.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

use common::{files_under as files, temp_dir, wait_until};

/// The environment variable that sets the seed of the kill moment.
const SEED_VAR: &str = "COMETS_RESUME_SEED";

/// The seed when [`SEED_VAR`] is not set.
const DEFAULT_SEED: u64 = 41;

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

/// `particles comets SPEC --out OUT`, its output discarded.
fn comets(spec: &Path, out: &Path) -> Command {
    let args = [
        "comets".as_ref(),
        spec.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    let mut c = common::particles::<_, &std::ffi::OsStr>(args, &std::env::temp_dir(), &[]);
    c.stdout(Stdio::null()).stderr(Stdio::null());
    c
}

/// The seed of the kill moment: [`SEED_VAR`] if set (an integer), else [`DEFAULT_SEED`].
fn seed() -> u64 {
    match std::env::var(SEED_VAR) {
        Ok(v) => v
            .trim()
            .parse()
            .unwrap_or_else(|e| panic!("{SEED_VAR}={v:?} is not an unsigned integer: {e}")),
        Err(_) => DEFAULT_SEED,
    }
}

/// A pseudo-random fraction in [0.05, 0.95) from `seed` (SplitMix64's output function).
fn fraction_of(seed: u64) -> f64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    0.05 + 0.9 * ((z >> 11) as f64 / (1u64 << 53) as f64)
}

#[test]
fn a_killed_population_study_resumes_to_identical_files() {
    let seed = seed();
    eprintln!("{SEED_VAR}={seed} (the kill moment; set it to replay a failure or try another)");
    let dir = temp_dir("particles-comets-resume", "killed");
    let spec = dir.join("population.toml");
    std::fs::write(&spec, spec_text()).unwrap();
    let (straight, resumed) = (dir.join("straight"), dir.join("resumed"));

    let t0 = Instant::now();
    assert!(comets(&spec, &straight).status().unwrap().success());
    let straight_time = t0.elapsed();

    // Kill at a moment of the run drawn from the seed (after its first checkpoint, so that
    // something is resumed); if the run ends first, try again with a shorter delay.
    let mut killed = false;
    for attempt in 0..6 {
        let fraction = fraction_of(seed) / f64::from(1u32 << attempt);
        eprintln!("attempt {attempt}: SIGKILL {fraction:.3} of the straight run's {straight_time:?} after the first checkpoint");
        let mut child = comets(&spec, &resumed).spawn().unwrap();
        let checkpoint = resumed.join("checkpoint.json");
        wait_until(&mut child, "the study's first checkpoint", || {
            checkpoint.exists()
        });
        // The kill moment itself (a drawn delay, not a wait for the child to be ready).
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
    assert!(
        killed,
        "the study always ended before it could be killed ({SEED_VAR}={seed})"
    );
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

    assert!(
        comets(&spec, &resumed).status().unwrap().success(),
        "the rerun failed ({SEED_VAR}={seed})"
    );
    let (a, b) = (files(&straight), files(&resumed));
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(
        names(&a),
        names(&b),
        "the resumed study wrote other files ({SEED_VAR}={seed})"
    );
    assert!(a.iter().any(|f| f.0.ends_with("final.parquet")) && a.len() >= 12);
    for ((name, da), (_, db)) in a.iter().zip(&b) {
        assert!(
            da == db,
            "{name} differs after the kill and the rerun ({SEED_VAR}={seed})"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
