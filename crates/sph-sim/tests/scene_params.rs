//! Each shipped scene (`scenes/*.toml`) builds the same solver parameters: the parameters in
//! `f64` and `f32` (checked, `Scene::solver_params`), the density kernel and the boundary
//! model, for the scene as written, with its `[quick]` overrides, carried over to every
//! other solver kind (`SolverSpec::with_kind`, as the fluid and boundary experiments do) and
//! with the edits the validation experiments make to shipped scenes (iteration counts,
//! XSPH, vorticity, the pressure clamp, the friction angle and cone, tolerances). The
//! snapshots were taken before the solver settings moved into the solver crates; they must
//! not change when the path from file to parameters is rebuilt. The test reads the
//! workspace's `scenes/`, so this file stays out of the published package.

use std::fmt::Write;
use std::path::{Path, PathBuf};

use sph_scene::{Scene, SolverKind, SolverSpec};
use sph_sim::density_kernel;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// The parameters `scene` builds in `f64` and `f32`, its density kernel and boundary model,
/// one line each.
fn describe(out: &mut String, label: &str, scene: &Scene) {
    let kernel = density_kernel(scene);
    writeln!(
        out,
        "[{label}] kind {} kernel {kernel:?} boundary {:?}",
        scene.solver.kind_name(),
        scene.boundary.model
    )
    .unwrap();
    match scene.solver_params::<f64>() {
        Ok(p) => writeln!(out, "  f64 {p:?}").unwrap(),
        Err(e) => writeln!(out, "  f64 error: {e}").unwrap(),
    }
    match scene.solver_params::<f32>() {
        Ok(p) => writeln!(out, "  f32 {p:?}").unwrap(),
        Err(e) => writeln!(out, "  f32 error: {e}").unwrap(),
    }
}

/// The variants of `scene` the validation experiments build (by editing the typed scene).
fn edited(scene: &Scene) -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    for kind in [
        SolverKind::Pbf,
        SolverKind::Pcisph,
        SolverKind::Iisph,
        SolverKind::Granular,
    ] {
        let mut s = scene.clone();
        s.solver = s.solver.with_kind(kind);
        out.push((format!("with_kind {}", kind.name()), s.clone()));
        // `fluid_runs::run_fluid` and `boundary_rest`: substeps and iterations set.
        s.solver.common_mut().substeps = 10;
        s.solver.set_iterations(4);
        out.push((
            format!("with_kind {} substeps 10 iterations 4", kind.name()),
            s,
        ));
    }
    let mut s = scene.clone();
    match &mut s.solver {
        // `dam_break_front` (no XSPH) and `pbf_vorticity` (ε).
        SolverSpec::Pbf(p) => {
            p.xsph_c = Some(0.0);
            p.vorticity_epsilon = Some(0.05);
            p.mean_compression_tolerance = Some(0.001);
        }
        // `pbf_stability`: the pressure clamp off.
        SolverSpec::Pcisph(p) => p.clamp_negative_pressure = Some(false),
        // `iisph_convergence`: a tolerance.
        SolverSpec::Iisph(p) => p.iisph.density_error_tolerance = Some(1e-5),
        // `granular_repose` and `granular_performance`: angle and cone.
        SolverSpec::Granular(g) => {
            g.friction_angle_deg = 35.0;
            g.cone_match = Some(iisph_granular::ConeMatch::PlaneStrain);
            g.iisph.density_error_tolerance = Some(1e-4);
        }
        SolverSpec::Elastoplastic(e) => e.friction_angle_deg = 35.0,
    }
    out.push(("edited settings".to_string(), s));
    out
}

/// The shipped scene files, sorted.
fn shipped_scenes() -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 11, "{paths:?}");
    paths
}

#[test]
fn shipped_scenes_build_the_same_parameters() {
    for path in shipped_scenes() {
        let scene = Scene::load(&path).unwrap();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let mut out = String::new();
        describe(&mut out, "scene", &scene);
        describe(&mut out, "quick", &scene.quick());
        for (label, s) in edited(&scene) {
            describe(&mut out, &label, &s);
        }
        insta::assert_snapshot!(name, out);
    }
}

/// The label the registration gives each solver kind (`SolverKind::label`, from the
/// settings' `SolverSettings::LABEL`) is the name the built solver gives itself
/// (`FluidSolver::name`): for the first shipped scene of every kind, or the dam break
/// carried over to a kind no scene ships (`SolverSpec::with_kind`).
#[test]
fn each_kind_is_labelled_as_its_solver_names_itself() {
    let scenes: Vec<Scene> = shipped_scenes()
        .iter()
        .map(|p| Scene::load(p).unwrap().quick())
        .collect();
    let dam_break = scenes.iter().find(|s| s.name == "dam_break").unwrap();
    for &kind in SolverKind::ALL {
        let scene = match scenes.iter().find(|s| s.solver.kind() == kind) {
            Some(s) => s.clone(),
            None => {
                let mut s = dam_break.clone();
                s.solver = s.solver.with_kind(kind);
                s
            }
        };
        let sim = sph_sim::SceneSim::<f32>::new(&scene).unwrap();
        assert_eq!(kind.label(), sim.solver().name(), "{}", scene.name);
    }
}
