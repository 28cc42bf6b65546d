//! How a run through the one frame loop ends: completed, stopped by an observer (after every
//! observer has seen the frame), interrupted, diverged by an observer's judgement or by the
//! solver's blow-up, which is kept as an outcome with the state of its last good substep.

use std::path::PathBuf;

use granular_measure::RestSettings;
use sph_core::Vec3;
use sph_scene::Scene;
use sph_sim::observe::{DensityLimit, OnFrame, Recorder, RestCriterion, RestObserver, Snapshots};
use sph_sim::{run_frames, Divergence, Ending, Flow, FrameRecord, RunPlan, SceneSim};

const SCENE: &str = r#"
name = "tiny"
[simulation]
precision = "f64"
particle_spacing = 0.025
duration = 0.16
frame_dt = 0.016
[solver]
kind = "pbf"
substeps = 2
iterations = 2
[tank]
min = [0.0, 0.0, 0.0]
max = [0.3, 0.3, 0.2]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.1, 0.15, 0.1]
"#;

fn sim(test: &str) -> SceneSim<f64> {
    let dir = std::env::temp_dir().join(format!("sph-sim-outcomes-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path: PathBuf = dir.join("tiny.toml");
    std::fs::write(&path, SCENE).unwrap();
    SceneSim::new(&Scene::load(&path).unwrap()).unwrap()
}

#[test]
fn a_run_completes_at_its_last_frame_with_a_record_per_frame() {
    let mut sim = sim("completes");
    let mut rec = Recorder::default();
    let mut snaps = Snapshots::at(&[0, 3]);
    let plan = RunPlan::next(&sim, 4);
    let out = run_frames(&mut sim, &plan, &mut [&mut rec, &mut snaps]).unwrap();
    assert!(out.completed() && out.ending.name() == "completed");
    assert_eq!((out.frame, sim.frame), (4, 4));
    let frames: Vec<usize> = rec.records.iter().map(|r| r.frame).collect();
    assert_eq!(frames, [1, 2, 3, 4]);
    assert!(rec
        .records
        .iter()
        .all(|r| r.particles == 96 && r.substeps == 2));
    let snapped: Vec<usize> = snaps.taken.iter().map(|(f, _)| *f).collect();
    assert_eq!(snapped, [0, 3]);
    // The record's largest speed is that of the state at the frame's end.
    let v_max = sim
        .state
        .velocities
        .iter()
        .map(|v| v.norm())
        .fold(0.0, f64::max);
    assert_eq!(rec.records[3].max_speed_m_s, v_max);
}

#[test]
fn an_observer_stops_the_run_after_every_observer_saw_the_frame() {
    let mut sim = sim("stops");
    let mut stop = OnFrame(|sim: &SceneSim<f64>, _: &FrameRecord| match sim.frame {
        2 => Flow::Stop("enough".into()),
        _ => Flow::Continue,
    });
    let mut rec = Recorder::default();
    let plan = RunPlan::next(&sim, 10);
    let out = run_frames(&mut sim, &plan, &mut [&mut stop, &mut rec]).unwrap();
    assert!(matches!(&out.ending, Ending::Stopped { reason } if reason == "enough"));
    assert_eq!((out.frame, rec.records.len()), (2, 2));
    // The simulation goes on from there.
    let plan = RunPlan::next(&sim, 1);
    let out = run_frames(&mut sim, &plan, &mut []).unwrap();
    assert!(out.completed() && sim.frame == 3);
}

#[test]
fn an_interrupt_and_a_density_limit_are_outcomes() {
    let mut sim = sim("interrupt");
    let mut interrupt = OnFrame(|_: &SceneSim<f64>, _: &FrameRecord| Flow::Interrupt);
    let plan = RunPlan::next(&sim, 5);
    let out = run_frames(&mut sim, &plan, &mut [&mut interrupt]).unwrap();
    assert!(matches!(out.ending, Ending::Interrupted) && out.frame == 1);

    // No liquid at rest has max rho/rho0 below 0.5: the limit ends the run as diverged.
    let mut limit = DensityLimit { limit: 0.5 };
    let plan = RunPlan::next(&sim, 5);
    let out = run_frames(&mut sim, &plan, &mut [&mut limit]).unwrap();
    let d = out.divergence().expect("diverged");
    assert!(matches!(d, Divergence::Observed(_)) && d.step_and_particle().is_none());
    assert!(d.to_string().contains("max rho/rho0"), "{d}");
    assert_eq!(out.frame, 2);
}

#[test]
fn a_blow_up_is_kept_as_an_outcome_naming_the_step_and_particle() {
    let mut sim = sim("blow_up");
    let plan = RunPlan::next(&sim, 2);
    run_frames(&mut sim, &plan, &mut []).unwrap();
    // A particle thrown at an absurd speed leaves every grid the search can build.
    sim.state.velocities[5] = Vec3::new(1e300, 0.0, 0.0);
    let mut rec = Recorder::default();
    let plan = RunPlan::next(&sim, 3);
    let out = run_frames(&mut sim, &plan, &mut [&mut rec]).unwrap();
    let d = out.divergence().expect("diverged");
    assert!(matches!(d, Divergence::Solver(_)), "{d}");
    assert!(d.step_and_particle().is_some(), "{d}");
    assert!(d.to_string().contains("frame 2"), "{d}");
    assert_eq!((out.frame, rec.records.len()), (2, 0));
    assert!(sim
        .state
        .positions
        .iter()
        .all(|p| p.iter().all(|x| x.is_finite())));
    // For a caller to which a blow-up is a failure, it is the solver's error.
    let err = out.diverged_as_error().unwrap_err();
    assert!(err.to_string().contains("blow-up"), "{err}");
}

/// The speeds only (the water block has no slope), under a bound of about 5 km/s that every
/// particle is below, held `hold_s`.
fn speeds_only(hold_s: f64) -> RestCriterion {
    RestCriterion {
        settings: RestSettings {
            speed_scale: 1e4,
            speed_hold_s: hold_s,
            angle_drift_deg: None,
            ..RestSettings::default()
        },
        ..RestCriterion::default()
    }
}

#[test]
fn rest_stops_the_run_once_the_speeds_held_below_the_bound() {
    let mut sim = sim("rest");
    // Sampled at t = 0 and after each frame: at rest from t = 0, held 0.03 s.
    let mut rest = RestObserver::new(speeds_only(0.03));
    let plan = RunPlan::next(&sim, 10);
    let out = run_frames(&mut sim, &plan, &mut [&mut rest]).unwrap();
    assert!(matches!(out.ending, Ending::Stopped { .. }), "{out:?}");
    // 0.032 s >= 0.03 s after frame 2.
    assert_eq!((out.frame, rest.samples.len()), (2, 3));
    assert_eq!(rest.rest_from_s, Some(0.0));
    let v = rest.verdict.unwrap();
    assert!(v.at_rest && v.angle_drift.is_none());
    assert!((v.percentile_speed.bound - 1e4 * (9.81f64 * 0.025).sqrt()).abs() < 1e-9);
}

#[test]
fn a_block_of_water_is_never_a_heap_at_rest() {
    // The angle judged: a flat block has no flank to measure, so the angle's drift is
    // never measured and the verdict says so, however slow the particles.
    let mut sim = sim("rest-angle");
    let mut criterion = speeds_only(0.03);
    criterion.settings.angle_drift_deg = Some(0.3);
    criterion.settings.angle_window_s = 0.05;
    let mut rest = RestObserver::new(criterion);
    let plan = RunPlan::next(&sim, 5);
    let out = run_frames(&mut sim, &plan, &mut [&mut rest]).unwrap();
    assert!(matches!(out.ending, Ending::Completed), "{out:?}");
    let v = rest.verdict.unwrap();
    assert!(!v.at_rest && v.angle_drift.unwrap().value.is_nan());
    assert!(v
        .summary(&criterion.settings)
        .contains("angle_drift not measured"));
}

#[test]
fn a_resumed_rest_hold_stops_where_the_whole_run_does() {
    let criterion = speeds_only(0.04);
    // Whole: at rest from t = 0, 0.048 s >= 0.04 s after frame 3.
    let mut whole = sim("rest-whole");
    let mut rest = RestObserver::new(criterion);
    let plan = RunPlan::next(&whole, 10);
    let out = run_frames(&mut whole, &plan, &mut [&mut rest]).unwrap();
    assert_eq!((out.frame, rest.rest_from_s), (3, Some(0.0)));
    // Split after frame 1: the second run continues from the first's samples.
    let mut split = sim("rest-split");
    let mut first = RestObserver::new(criterion);
    let plan = RunPlan::next(&split, 1);
    let out = run_frames(&mut split, &plan, &mut [&mut first]).unwrap();
    assert_eq!((out.frame, first.rest_from_s), (1, None));
    assert_eq!(first.below_since_s(), Some(0.0));
    let mut second = RestObserver::resumed(criterion, first.carried());
    let plan = RunPlan::next(&split, 10);
    let out = run_frames(&mut split, &plan, &mut [&mut second]).unwrap();
    assert_eq!((out.frame, second.rest_from_s), (3, Some(0.0)));
    assert_eq!(second.verdict, rest.verdict);
    // A fresh observer starts the hold at the second run's first state instead.
    let mut again = sim("rest-fresh");
    let mut first = RestObserver::new(criterion);
    let plan = RunPlan::next(&again, 1);
    run_frames(&mut again, &plan, &mut [&mut first]).unwrap();
    let mut fresh = RestObserver::new(criterion);
    let plan = RunPlan::next(&again, 10);
    let out = run_frames(&mut again, &plan, &mut [&mut fresh]).unwrap();
    assert_eq!(out.frame, 4);
    let from = fresh.rest_from_s.unwrap();
    assert!((from - 0.016).abs() < 1e-12, "{from}");
}
