//! Population files (features `io` and `parquet`): bad input gets a named error with line and column and
//! nothing is written; a study resumes bit for bit.
#![cfg(feature = "parquet")]

use std::path::{Path, PathBuf};

use symplectic::io::{check_memory, read_particle_rows, ParticleKind};
use symplectic::study::run_study;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("population-io-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    std::fs::create_dir_all(&d).unwrap();
    d
}

const SPEC: &str = r#"
[planets]
system = "outer_solar_system"
frame = "ecliptic_j2000"
scheme = "s2"
step_days = 365.25

[integrator]
variant = "barycentric"
scheme = "s2"
b1 = 0.21e-6
initial_step_days = 365.25
window_steps = 7

[particles]
file = "p.csv"
kind = "barycentric_elements"

[span]
years = 120.0
snapshot_every_years = 50.0
checkpoint_every_years = 20.0

[removal]
hill_factor = 1.0
min_perihelion = 26.0
"#;

const GOOD_ROWS: &str = "id,a,e,i,node,peri,mean_anomaly\n\
    0,60.0,0.4,10.0,20.0,30.0,40.0\n\
    1,80.0,0.5,5.0,120.0,230.0,300.0\n\
    2,-200.0,1.2,3.0,10.0,10.0,1.0\n";

/// Writes the specification and particle file into a fresh directory.
fn study(name: &str, spec: &str, rows: &str) -> (PathBuf, PathBuf) {
    let dir = temp_dir(name);
    std::fs::write(dir.join("study.toml"), spec).unwrap();
    std::fs::write(dir.join("p.csv"), rows).unwrap();
    (dir.join("study.toml"), dir.join("out"))
}

/// The error of a bad study, with the temporary directory replaced; checks nothing was
/// written.
fn bad_study(name: &str, spec: &str, rows: &str) -> String {
    let (spec_path, out) = study(name, spec, rows);
    let err = run_study(&spec_path, &out, |_| {}).unwrap_err().to_string();
    assert!(!out.exists(), "{name}: output written despite {err}");
    let dir = spec_path.parent().unwrap().display().to_string();
    err.replace(&dir, "DIR")
}

#[test]
fn bad_particle_files_name_line_and_column() {
    let header = "id,a,e,i,node,peri,mean_anomaly\n0,60.0,0.4,10.0,20.0,30.0,40.0\n";
    insta::assert_snapshot!(
        "nan",
        bad_study("nan", SPEC, &format!("{header}1,NaN,0.4,1,2,3,4\n"))
    );
    insta::assert_snapshot!(
        "bound_unbound",
        bad_study("bound", SPEC, &format!("{header}1,60.0,1.4,1,2,3,4\n"))
    );
    insta::assert_snapshot!(
        "missing_column",
        bad_study("missing", SPEC, "id,a,e,i,node,peri\n0,60,0.4,1,2,3\n")
    );
    insta::assert_snapshot!(
        "duplicate_id",
        bad_study("dup", SPEC, &format!("{header}0,70.0,0.4,1,2,3,4\n"))
    );
    let states = SPEC.replace("barycentric_elements", "barycentric_state");
    insta::assert_snapshot!(
        "zero_distance",
        bad_study("zero", &states, "id,x,y,z,vx,vy,vz\n0,0,0,0,0.001,0,0\n")
    );
}

#[test]
fn bad_specifications_name_the_field() {
    insta::assert_snapshot!(
        "epoch_outside",
        bad_study(
            "epoch",
            &SPEC.replace(
                "kind = \"barycentric_elements\"",
                "kind = \"barycentric_elements\"\nepoch_days = -10.0"
            ),
            GOOD_ROWS
        )
    );
    insta::assert_snapshot!(
        "unknown_field",
        bad_study(
            "unknown",
            &SPEC.replace("b1 = 0.21e-6", "b1 = 0.21e-6\nb2 = 1.0"),
            GOOD_ROWS
        )
    );
    insta::assert_snapshot!(
        "bad_variant",
        bad_study(
            "variant",
            &SPEC.replace("\"barycentric\"", "\"heliocentric\""),
            GOOD_ROWS
        )
    );
    insta::assert_snapshot!(
        "negative_span",
        bad_study(
            "span",
            &SPEC.replace("years = 120.0", "years = -1.0"),
            GOOD_ROWS
        )
    );
}

#[test]
fn a_population_too_large_is_refused_with_the_figure() {
    insta::assert_snapshot!(
        "out_of_memory",
        check_memory(1_000_000_000, Some(8 << 30))
            .unwrap_err()
            .to_string()
    );
    assert!(check_memory(1000, Some(8 << 30)).is_ok());
}

#[test]
fn elements_and_states_read_back() {
    let dir = temp_dir("rows");
    let p = dir.join("p.csv");
    std::fs::write(&p, GOOD_ROWS).unwrap();
    let rows = read_particle_rows(&p, ParticleKind::BarycentricElements).unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[2].line, 4);
    assert_eq!(rows[2].values[0], -200.0);
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for e in walk(dir) {
        out.push((
            e.strip_prefix(dir).unwrap().display().to_string(),
            std::fs::read(&e).unwrap(),
        ));
    }
    out.sort();
    out
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            v.extend(walk(&p));
        } else {
            v.push(p);
        }
    }
    v
}

/// A study interrupted after any checkpoint and rerun writes the same files, byte for byte.
#[test]
fn a_resumed_study_writes_identical_files() {
    let (spec, out) = study("resume", SPEC, GOOD_ROWS);
    let summary = run_study(&spec, &out, |_| {}).unwrap();
    assert!(!summary.resumed);
    assert_eq!(summary.snapshots_written, 4); // 0, 50, 100, 120 years
    let straight = files(&out);
    // Interrupt after k synchronisation windows (a panic in the callback stands for kill -9:
    // the files are those written so far), rerun, compare.
    for k in [1, 3, 6, 11] {
        let (spec2, out2) = study(&format!("resume{k}"), SPEC, GOOD_ROWS);
        let mut calls = 0;
        let interrupted = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            run_study(&spec2, &out2, |_| {
                calls += 1;
                assert!(calls < k, "interrupted");
            })
        }));
        assert!(interrupted.is_err(), "k = {k}: not interrupted");
        // Resumed if killed after the first checkpoint (20 years), started afresh before.
        let checkpointed = out2.join("checkpoint.json").exists();
        let resumed = run_study(&spec2, &out2, |_| {}).unwrap();
        assert_eq!(resumed.resumed, checkpointed, "k = {k}");
        assert_eq!(files(&out2), straight, "k = {k}: resumed files differ");
    }
    // Rerun over a finished directory: resumes, rewrites the same files.
    let again = run_study(&spec, &out, |_| {}).unwrap();
    assert!(again.resumed);
    assert_eq!(files(&out), straight);
}

/// Checkpoints at their own cadence, not at every snapshot: snapshots every 10 years and
/// checkpoints every 30 over 120 years write 13 snapshots and 4 checkpoints (30, 60, 90 and
/// 120 years, the last also the end). A run killed at 45 years (after the snapshot at 40,
/// before the checkpoint at 60) left the checkpoint of 30 years, older than the last
/// snapshot; resumed from it, it rewrites the snapshots from 40 years on and ends with the
/// files of the uninterrupted run, byte for byte.
#[test]
fn checkpoints_follow_their_own_cadence_and_resume_across_snapshots() {
    let spec = with(
        SPEC,
        "snapshot_every_years = 50.0",
        "snapshot_every_years = 10.0",
    );
    let spec = with(
        &spec,
        "checkpoint_every_years = 20.0",
        "checkpoint_every_years = 30.0",
    );
    let (spec_path, out) = study("cadence", &spec, GOOD_ROWS);
    let straight = run_study(&spec_path, &out, |_| {}).unwrap();
    assert_eq!(
        (straight.snapshots_written, straight.checkpoints_written),
        (13, 4)
    );
    let straight_files = files(&out);

    let (spec2, out2) = study("cadence-killed", &spec, GOOD_ROWS);
    let killed_at = 45.0 * 365.25;
    // A panic in the callback stands for kill -9: the files are those written so far.
    let killed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run_study(&spec2, &out2, |p| {
            assert!(p.time < killed_at, "killed");
        })
    }));
    assert!(killed.is_err(), "not killed");
    // The checkpoint on disk is the one of 30 years: not rewritten at the snapshots of 40
    // years (written, below) or at any snapshot before.
    let checkpoint: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out2.join("checkpoint.json")).unwrap()).unwrap();
    assert_eq!(checkpoint["population"]["time"], 30.0 * 365.25);
    assert_eq!(
        checkpoint["next_snapshot"], 4,
        "snapshots 0–30 years before it"
    );
    assert_eq!(checkpoint["next_checkpoint"], 2);
    assert!(
        out2.join("snapshots/snapshot_000004.parquet").exists(),
        "40 years"
    );
    let resumed = run_study(&spec2, &out2, |_| {}).unwrap();
    assert!(resumed.resumed);
    // Snapshots 40–120 years (9) again; checkpoints at 60, 90 and 120 years.
    assert_eq!(
        (resumed.snapshots_written, resumed.checkpoints_written),
        (9, 3)
    );
    assert_eq!(files(&out2), straight_files, "resumed files differ");
}

/// Rows given directly build the same population as the particle file they came from, and
/// are checked as the file's rows are (a non-finite value, `a` and `e` that disagree).
#[test]
fn rows_given_directly_build_the_files_population() {
    use symplectic::io::{ParticleRow, PopulationSpec};
    let dir = temp_dir("rows");
    let spec_path = dir.join("spec.toml");
    std::fs::write(&spec_path, SPEC).unwrap();
    std::fs::write(dir.join("p.csv"), GOOD_ROWS).unwrap();
    let spec = PopulationSpec::from_file(&spec_path).unwrap();
    let from_file = spec.population(&spec_path).unwrap();
    let rows = read_particle_rows(&dir.join("p.csv"), ParticleKind::BarycentricElements).unwrap();
    let direct = spec
        .population_from_rows(&rows, Path::new("array"))
        .unwrap();
    assert_eq!(direct.members(), from_file.members());
    assert_eq!(direct.window_steps(), 7);

    let mut bad = rows.clone();
    bad[1].values[2] = f64::NAN;
    let err = spec
        .population_from_rows(&bad, Path::new("array"))
        .unwrap_err();
    assert!(err.to_string().contains("not a finite number"), "{err}");
    let mut bad: Vec<ParticleRow> = rows.clone();
    bad[0].values[1] = 1.5;
    let err = spec
        .population_from_rows(&bad, Path::new("array"))
        .unwrap_err();
    assert!(err.to_string().contains("bound"), "{err}");
}

/// A study with an `[encounters]` table builds a population integrated through encounters,
/// and its table carries the region, Levison's class, the Tisserand parameter, the encounter
/// flag and the count of encounters begun; an
/// `[encounters]` table together with the Hill-sphere removal rule is refused by name.
#[test]
fn a_study_with_encounters_integrates_through_them() {
    use symplectic::io::{population_table, PopulationSpec};
    let spec_text = SPEC.replace("b1 = 0.21e-6", "b1 = 4e-6").replace(
        "hill_factor = 1.0\nmin_perihelion = 26.0",
        "min_perihelion = 2.5",
    ) + "\n[encounters]\n";
    let rows = "id,a,e,i,node,peri,mean_anomaly\n\
        0,14.0,0.17,2.2,334.0,262.0,65.0\n\
        1,5.6,0.05,3.0,20.0,30.0,40.0\n\
        2,9.0,0.1,1.0,120.0,230.0,300.0\n";
    let (path, _) = study("encounters", &spec_text, rows);
    let spec = PopulationSpec::from_file(&path).unwrap();
    let mut pop = spec.population(&path).unwrap();
    assert_eq!(pop.encounters(), Some(symplectic::Encounters::default()));
    pop.advance_to(5.0 * 365.25, |_| {}).unwrap();
    let table = population_table(&pop).unwrap();
    let schema = table.schema();
    for column in [
        "tisserand_jupiter",
        "region",
        "levison_class",
        "in_encounter",
        "encounters_begun",
    ] {
        assert!(schema.field_with_name(column).is_ok(), "{column}");
    }
    let labels = |column: &str| {
        table
            .column_by_name(column)
            .unwrap()
            .as_any()
            .downcast_ref::<arrow_array::StringArray>()
            .unwrap()
            .clone()
    };
    // a = 14 AU, q = 11.6 AU: between the giants. T_J = 5.203/14 + 2 cos 2.2° √((14/5.203)
    // (1 − 0.17²)) = 3.60 from the initial elements (five years on, within a few 0.01: the
    // comet meets no planet closer than Saturn's Hill sphere): T_J > 3 and a > a_J,
    // Chiron-type.
    assert_eq!(labels("region").value(0), "centaur");
    assert_eq!(labels("levison_class").value(0), "chiron_type");
    let t_j = table
        .column_by_name("tisserand_jupiter")
        .unwrap()
        .as_any()
        .downcast_ref::<arrow_array::Float64Array>()
        .unwrap()
        .value(0);
    assert!((t_j - 3.60).abs() < 0.1, "T_J = {t_j}");
    let both = spec_text.replace("[removal]\n", "[removal]\nhill_factor = 1.0\n");
    let (bad, _) = study("encounters-bad", &both, rows);
    let err = PopulationSpec::from_file(&bad)
        .unwrap()
        .population(&bad)
        .unwrap_err();
    assert!(err.to_string().contains("hill_factor"), "{err}");
}

/// `key = old` replaced by `key = new` in the specification text.
fn with(spec: &str, old: &str, new: &str) -> String {
    assert!(spec.contains(old), "{old} not in the specification");
    spec.replace(old, new)
}

#[test]
fn specification_limits_name_the_key_and_the_bound() {
    // A planet step of 10⁻⁶ days against particle steps of a year: 3.7·10⁸ grid states of
    // one particle step (130 GB) before the first window, where the run used to allocate
    // without end.
    let e = bad_study(
        "tiny_planet_step",
        &with(SPEC, "\nstep_days = 365.25", "\nstep_days = 1e-6"),
        GOOD_ROWS,
    );
    assert!(
        e.contains("`planets.step_days`")
            && e.contains("MAX_STEP_GRID_BYTES")
            && e.contains("take at least"),
        "{e}"
    );
    // A first step that does not move the clock of the first window's end in f64.
    let e = bad_study(
        "tiny_first_step",
        &with(
            SPEC,
            "initial_step_days = 365.25",
            "initial_step_days = 1e-300",
        ),
        GOOD_ROWS,
    );
    assert!(
        e.contains("`integrator.initial_step_days`") && e.contains("no progress in f64"),
        "{e}"
    );
    // A snapshot cadence of 10⁻⁶ years over 120 years: 1.2·10⁸ Parquet files.
    let e = bad_study(
        "snapshot_flood",
        &with(
            SPEC,
            "snapshot_every_years = 50.0",
            "snapshot_every_years = 1e-6",
        ),
        GOOD_ROWS,
    );
    // The requested count, ⌈120/10⁻⁶⌉ + 1 = 120000001 (120/1e-6 rounds to 1.2·10⁸ exactly
    // in IEEE double, as Python's float division gives), and the cap.
    assert!(
        e.contains("`span.snapshot_every_years`")
            && e.contains(" 120000001 snapshot files")
            && e.contains("the cap of 10000 per study (MAX_SNAPSHOTS)"),
        "{e}"
    );
    // Just over the cap: 120 years every 0.012 is ⌈10000⌉ + 1 = 10001 files (120/0.012
    // rounds to 10000 exactly in IEEE double, as Python's float division gives).
    let e = bad_study(
        "snapshot_cap",
        &with(
            SPEC,
            "snapshot_every_years = 50.0",
            "snapshot_every_years = 0.012",
        ),
        GOOD_ROWS,
    );
    assert!(
        e.contains(" 10001 snapshot files") && e.contains("cap of 10000"),
        "{e}"
    );
    let e = bad_study(
        "checkpoint_flood",
        &with(
            SPEC,
            "checkpoint_every_years = 20.0",
            "checkpoint_every_years = 1e-9",
        ),
        GOOD_ROWS,
    );
    assert!(
        e.contains("`span.checkpoint_every_years`") && e.contains("MAX_CHECKPOINTS"),
        "{e}"
    );
    // At the limits' edges the specification is taken (the spec and its particles only).
    let (spec_path, _) = study(
        "limits_edge",
        &with(
            SPEC,
            "snapshot_every_years = 50.0",
            "snapshot_every_years = 0.0121",
        ),
        GOOD_ROWS,
    );
    symplectic::io::PopulationSpec::from_file(&spec_path).unwrap();
}

/// A named pipe at `path` (`mkfifo`), or `None` where there is none.
fn fifo(path: &Path) -> Option<()> {
    let ok = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .ok()?
        .success();
    ok.then_some(())
}

#[test]
fn devices_pipes_and_huge_files_are_refused_before_they_are_read() {
    // Nothing is read: each refusal is the one that comes from the metadata, before the
    // file is opened (`guard::regular_file_size`). That is checked by the messages, not by
    // a time bound (speed is measured in benchmarks, never asserted in a test): a reader that
    // read first would block on the FIFO, or read /dev/zero up to its limit and fail with
    // another message, and would call the big file one that "grew past" its limit "while
    // read" instead of naming its size from its metadata.
    use symplectic::io::{PopulationSpec, MAX_SPEC_FILE_BYTES};
    // The specification: /dev/zero never ends (8 GB read before), a FIFO blocks in open().
    let e = PopulationSpec::from_file(Path::new("/dev/zero"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("is a device, not a regular file"), "{e}");
    let dir = temp_dir("fifo");
    if fifo(&dir.join("spec.toml")).is_some() {
        let e = PopulationSpec::from_file(&dir.join("spec.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("named pipe (FIFO)"), "{e}");
        let e = read_particle_rows(&dir.join("spec.toml"), ParticleKind::BarycentricElements)
            .unwrap_err()
            .to_string();
        assert!(e.contains("named pipe (FIFO)"), "{e}");
    }
    // A specification larger than MAX_SPEC_FILE_BYTES, refused from its metadata.
    let big = dir.join("big.toml");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(MAX_SPEC_FILE_BYTES + 1).unwrap();
    let e = PopulationSpec::from_file(&big).unwrap_err().to_string();
    let from_metadata = format!(
        "{} bytes, more than the {MAX_SPEC_FILE_BYTES} bytes allowed (MAX_SPEC_FILE_BYTES)",
        MAX_SPEC_FILE_BYTES + 1
    );
    assert!(e.contains(&from_metadata), "{e}");
    // The particle file and a saved population.
    let e = read_particle_rows(Path::new("/dev/zero"), ParticleKind::BarycentricElements)
        .unwrap_err()
        .to_string();
    assert!(e.contains("is a device, not a regular file"), "{e}");
    let e = symplectic::Population::load(Path::new("/dev/zero"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("is a device, not a regular file"), "{e}");
}

mod elements_of_states {
    use proptest::prelude::*;
    use symplectic::io::conic_elements;
    use symplectic::kepler::{state_from_elements, ConicElements};

    proptest! {
        /// `conic_elements` inverts `state_from_elements` (the oracle: an independent
        /// forward map, Kepler's equation by Newton's method and three rotations): the state
        /// rebuilt from the recovered elements is the state. Tolerance 1e-9 relative: f64
        /// round-off (1e-16) amplified by Kepler's equation's conditioning, at most
        /// 1/(1 − e) = 20 for e ≤ 0.95, and by the hyperbolic functions' growth for
        /// |M| ≤ 10.
        #[test]
        fn round_trip(
            q in 1.0f64..100.0,
            e in prop_oneof![0.01f64..0.95, 1.05f64..3.0],
            i in 0.01f64..3.13,
            node in 0.0f64..std::f64::consts::TAU,
            peri in 0.0f64..std::f64::consts::TAU,
            m in -10.0f64..10.0,
        ) {
            let mu = 2.96e-4;
            let el = ConicElements { perihelion: q, eccentricity: e, inclination: i, node,
                argument_of_perihelion: peri, mean_anomaly: m };
            let (r, v) = state_from_elements(&el, mu).unwrap();
            let back = conic_elements(&r, &v, mu).unwrap();
            let (r2, v2) = state_from_elements(&back, mu).unwrap();
            prop_assert!((r2 - r).norm() <= 1e-9 * r.norm(), "{:?} -> {:?}", el, back);
            prop_assert!((v2 - v).norm() <= 1e-9 * v.norm(), "{:?} -> {:?}", el, back);
            prop_assert!((back.eccentricity - e).abs() <= 1e-9 * e);
            prop_assert!((back.inclination - i).abs() <= 1e-9);
        }
    }
}

/// A study with end rules and events: the `[removal]` keys `sun_collision`, `min_distance`,
/// `max_distance` and the `[events]` table are read, and `events.parquet` holds the events
/// of the population the specification builds, advanced to the end (byte for byte the
/// table written from it); a resumed study writes it again, identical.
#[test]
fn a_study_writes_the_events_table() {
    use symplectic::io::{events_table, write_parquet, PopulationSpec, EVENTS_TABLE};
    let spec_text = with(
        SPEC,
        "hill_factor = 1.0\nmin_perihelion = 26.0",
        "min_perihelion = 26.0\nsun_collision = true\n\
         min_distance = { distance = 20.0, frame = \"heliocentric\" }\n\
         max_distance = { distance = 400.0, frame = \"barycentric\" }\n\n\
         [events]\nperihelion_below = [50.0, 37.0]\ntisserand_crossing = true\n\
         close_approach = { au = 2.0 }\nmax_per_particle = 10",
    );
    let (path, out) = study("events", &spec_text, GOOD_ROWS);
    let summary = run_study(&path, &out, |_| {}).unwrap();
    // Row 0 (q = 36 AU) is below both values from its first step, row 1 (q = 40 AU) below
    // 50 AU.
    assert!(summary.events >= 3, "{} events", summary.events);
    let spec = PopulationSpec::from_file(&path).unwrap();
    assert_eq!(spec.events.perihelion_below, vec![50.0, 37.0]);
    let mut pop = spec.population(&path).unwrap();
    pop.advance_to(120.0 * 365.25, |_| {}).unwrap();
    let own = out.join("own-events.parquet");
    write_parquet(&own, &events_table(&pop).unwrap()).unwrap();
    let written = std::fs::read(out.join(EVENTS_TABLE)).unwrap();
    assert_eq!(written, std::fs::read(&own).unwrap());
    std::fs::remove_file(&own).unwrap();
    let before = files(&out);
    assert!(run_study(&path, &out, |_| {}).unwrap().resumed);
    assert_eq!(files(&out), before);
}

/// Bad end rules and event rules in a specification are refused with the file and the key.
#[test]
fn bad_end_rules_and_events_name_the_key() {
    for (name, old, new, key) in [
        (
            "min_distance",
            "min_perihelion = 26.0",
            "min_distance = { distance = -1.0 }",
            "removal.min_distance.distance",
        ),
        (
            "min_above_max",
            "min_perihelion = 26.0",
            "min_distance = { distance = 50.0 }\nmax_distance = { distance = 40.0 }",
            "removal.min_distance.distance",
        ),
        (
            "frame",
            "min_perihelion = 26.0",
            "max_distance = { distance = 50.0, frame = \"galactic\" }",
            "removal.max_distance.frame",
        ),
        (
            "perihelion_below",
            "min_perihelion = 26.0",
            "min_perihelion = 26.0\n[events]\nperihelion_below = [2.5, 0.0]",
            "events.perihelion_below",
        ),
        (
            "approach_unit",
            "min_perihelion = 26.0",
            "min_perihelion = 26.0\n[events]\nclose_approach = { parsecs = 1.0 }",
            "events.close_approach",
        ),
        (
            "approach_radius",
            "min_perihelion = 26.0",
            "min_perihelion = 26.0\n[events]\nclose_approach = { hill_radii = inf }",
            "events.close_approach.hill_radii",
        ),
        (
            "unknown_event",
            "min_perihelion = 26.0",
            "min_perihelion = 26.0\n[events]\nfirst_q = 2.5",
            "first_q",
        ),
    ] {
        let e = bad_study(&format!("events-{name}"), &with(SPEC, old, new), GOOD_ROWS);
        assert!(e.contains(key) && e.contains("study.toml"), "{name}: {e}");
    }
}
