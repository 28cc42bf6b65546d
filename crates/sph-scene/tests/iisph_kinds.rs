//! The IISPH kinds of the `[solver]` table (`kind = "iisph"` for water, `kind = "granular"`):
//! fields, defaults, and a named error with field path and line for every out-of-range
//! value.

mod common;

use common::{assert_names, err_with, fixture_dir};
use iisph_granular::DEFAULT_MAX_ITERATIONS;
use sph_scene::{Scene, SolverKind, SolverSpec};

/// The `[solver]` table of the fixture (`kind = "pbf"` … `xsph_c = 0.01`, lines 12–15).
const PBF_SOLVER: &str = "kind = \"pbf\"\nsubsteps = 2\niterations = 3\nxsph_c = 0.01";

fn with_solver(test: &str, solver: &str) -> Result<Scene, sph_scene::SceneError> {
    let text = common::VALID.replacen(PBF_SOLVER, solver, 1);
    Scene::parse_str(&text, &fixture_dir(test).join(format!("{test}.toml")))
}

#[test]
fn iisph_scene_reads_with_defaults() {
    let s = with_solver("iisph_ok", "kind = \"iisph\"\nsubsteps = 8").unwrap();
    assert_eq!(s.solver.kind(), SolverKind::Iisph);
    let SolverSpec::Iisph(p) = &s.solver else {
        panic!("{:?}", s.solver)
    };
    assert_eq!(p.common.substeps, 8);
    assert_eq!(p.iisph.max_iterations, None);
    assert_eq!(s.solver.iterations(), DEFAULT_MAX_ITERATIONS);
}

#[test]
fn granular_scene_reads_every_field() {
    let s = with_solver(
        "granular_ok",
        "kind = \"granular\"\nsubsteps = 4\nmax_iterations = 50\nmin_iterations = 3\n\
         density_error_tolerance = 0.0005\nrelaxation = 0.4\nviscosity = 1e-6\n\
         friction_angle_deg = 33.0\ndrag_coefficient = 0.47\nair_velocity = [1.0, 0.0, 0.0]\n\
         upscaling_factor = 8",
    )
    .unwrap();
    let SolverSpec::Granular(p) = &s.solver else {
        panic!("{:?}", s.solver)
    };
    assert_eq!(p.friction_angle_deg, 33.0);
    assert_eq!(p.drag_coefficient, Some(0.47));
    assert_eq!(p.air_velocity, Some([1.0, 0.0, 0.0]));
    assert_eq!(p.upscaling_factor, Some(8));
    assert_eq!(
        (p.iisph.max_iterations, p.iisph.min_iterations),
        (Some(50), Some(3))
    );
    // with_kind keeps the IISPH settings between the two IISPH kinds.
    let SolverSpec::Iisph(w) = s.solver.with_kind(SolverKind::Iisph) else {
        panic!()
    };
    assert_eq!(
        (w.common.substeps, w.iisph.relaxation, w.iisph.viscosity),
        (4, Some(0.4), Some(1e-6))
    );
}

#[test]
fn granular_needs_a_friction_angle() {
    let e = with_solver("granular_no_angle", "kind = \"granular\"\nsubsteps = 4").unwrap_err();
    assert_names(
        &e,
        "granular_no_angle",
        "solver.friction_angle_deg",
        "missing",
    );
}

#[test]
fn iisph_refuses_pbf_fields() {
    let e = err_with("iisph_iterations", "kind = \"pbf\"", "kind = \"iisph\"");
    assert_names(&e, "iisph_iterations", "solver.iterations", "line 14");
}

/// Each out-of-range value: the field path and its line (the solver table starts at
/// line 12: `kind` 12, `substeps` 13, the tested field 14).
#[test]
fn out_of_range_values_are_named_with_their_line() {
    let cases = [
        ("iisph", "substeps = 0", "substeps", ">= 1"),
        (
            "iisph",
            "substeps = 1\nmin_iterations = 0",
            "min_iterations",
            ">= 1",
        ),
        (
            "iisph",
            "substeps = 1\nmin_iterations = 5\nmax_iterations = 4",
            "max_iterations",
            "min_iterations = 5",
        ),
        (
            "iisph",
            "substeps = 1\nmax_iterations = 1",
            "max_iterations",
            "min_iterations = 2",
        ),
        (
            "iisph",
            "substeps = 1\ndensity_error_tolerance = 0.0",
            "density_error_tolerance",
            "> 0",
        ),
        (
            "iisph",
            "substeps = 1\nrelaxation = 1.5",
            "relaxation",
            "(0, 1]",
        ),
        (
            "iisph",
            "substeps = 1\nrelaxation = 0.0",
            "relaxation",
            "(0, 1]",
        ),
        (
            "iisph",
            "substeps = 1\nviscosity = -1.0",
            "viscosity",
            ">= 0",
        ),
        (
            "iisph",
            "substeps = 1\nrest_density = -5.0",
            "rest_density",
            "> 0",
        ),
        (
            "iisph",
            "substeps = 1\nsupport_over_spacing = 0.5",
            "support_over_spacing",
            "> 1",
        ),
        (
            "granular",
            "substeps = 1\nfriction_angle_deg = 90.0",
            "friction_angle_deg",
            "[0, 90)",
        ),
        (
            "granular",
            "substeps = 1\nfriction_angle_deg = -1.0",
            "friction_angle_deg",
            "[0, 90)",
        ),
        (
            "granular",
            "substeps = 1\nfriction_angle_deg = 30.0\ndrag_coefficient = -0.1",
            "drag_coefficient",
            ">= 0",
        ),
        (
            "granular",
            "substeps = 1\nfriction_angle_deg = 30.0\nupscaling_factor = 0",
            "upscaling_factor",
            ">= 1",
        ),
        (
            "granular",
            "substeps = 1\nfriction_angle_deg = 30.0\nair_velocity = [1.0, nan, 0.0]",
            "air_velocity",
            "not finite",
        ),
    ];
    for (k, (kind, fields, field, reason)) in cases.iter().enumerate() {
        let test = format!("iisph_range_{k}");
        let e = with_solver(&test, &format!("kind = \"{kind}\"\n{fields}")).unwrap_err();
        let line = 12 + fields.lines().position(|l| l.starts_with(field)).unwrap() + 1;
        assert_names(&e, &test, &format!("solver.{field}"), reason);
        assert!(e.to_string().contains(&format!("line {line}")), "{e}");
    }
}

#[test]
fn quick_iterations_below_the_minimum_refused() {
    let text = common::VALID
        .replacen(PBF_SOLVER, "kind = \"iisph\"\nsubsteps = 2", 1)
        .replacen("duration = 0.5", "duration = 0.5\niterations = 1", 1);
    let e =
        Scene::parse_str(&text, &fixture_dir("iisph_quick").join("iisph_quick.toml")).unwrap_err();
    assert_names(&e, "iisph_quick", "quick.iterations", "min_iterations = 2");
}

/// `cone_match` reads in kebab case, defaults to the thesis's plane-strain match, reaches
/// the solver's parameters, and a wrong name is refused at the field.
#[test]
fn granular_cone_match() {
    use iisph_granular::ConeMatch;
    use sph_scene::SolverParams;
    let granular = |extra: &str| {
        with_solver(
            "granular_cone",
            &format!("kind = \"granular\"\nsubsteps = 4\nfriction_angle_deg = 30.0{extra}"),
        )
    };
    let alpha = |s: &Scene| {
        let SolverParams::Granular(p) = s.solver_params::<f64>().unwrap() else {
            panic!("not granular")
        };
        p.granular.unwrap().alpha()
    };
    let s = granular("").unwrap();
    let SolverSpec::Granular(p) = &s.solver else {
        panic!("{:?}", s.solver)
    };
    assert_eq!(p.cone_match, None);
    assert!((alpha(&s) - iisph_granular::cone_alpha(ConeMatch::PlaneStrain, 30.0)).abs() < 1e-12);
    let s = granular("\ncone_match = \"simple-shear\"").unwrap();
    let SolverSpec::Granular(p) = &s.solver else {
        panic!("{:?}", s.solver)
    };
    assert_eq!(p.cone_match, Some(ConeMatch::SimpleShear));
    assert!((alpha(&s) - iisph_granular::cone_alpha(ConeMatch::SimpleShear, 30.0)).abs() < 1e-12);
    let e = granular("\ncone_match = \"simple_shear\"")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("solver.cone_match") && e.contains("simple-shear") && e.contains("line"),
        "{e}"
    );
}
