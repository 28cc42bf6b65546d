//! One test per kind of malformed scene: the error names the file, the field path and the
//! reason.

mod common;

use common::{assert_names, err_with, fixture_dir, VALID};
use sph_scene::{Scene, SceneError};

#[test]
fn valid_fixture_parses() {
    let dir = fixture_dir("valid");
    let s = Scene::parse_str(VALID, &dir.join("valid.toml")).unwrap();
    assert_eq!(s.fluids.len(), 2);
    assert_eq!(s.solids.len(), 2);
    let n = s.fluid_positions::<f64>().unwrap().len();
    // Block 10 x 10 x 20 + cube mesh of 0.2 m = 4³ lattice points.
    assert_eq!(n, 2000 + 64);
    let solids = s.build_solids::<f32>().unwrap();
    assert_eq!(solids.len(), 3);
    let q = s.quick();
    assert_eq!(q.fluid_positions::<f32>().unwrap().len(), 5 * 5 * 10 + 8);
}

#[test]
fn toml_syntax_error() {
    let e = err_with("syntax", "substeps = 2", "substeps = = 2");
    assert_names(&e, "syntax", "<document>", "(line 13, column 12)");
}

#[test]
fn wrong_type() {
    let e = err_with("wrong_type", "substeps = 2", "substeps = \"two\"");
    assert_names(&e, "wrong_type", "solver.substeps", "invalid type");
}

#[test]
fn negative_integer() {
    let e = err_with("negative_integer", "iterations = 3", "iterations = -3");
    assert_names(&e, "negative_integer", "solver.iterations", "invalid value");
}

#[test]
fn unknown_field() {
    let e = err_with("unknown_field", "xsph_c = 0.01", "xsph = 0.01");
    assert_names(&e, "unknown_field", "solver.xsph", "unknown field");
}

#[test]
fn unknown_field_in_array_of_tables() {
    let e = err_with(
        "unknown_fluid_field",
        "velocity = [0.0, 0.0, 0.0]",
        "speed = 1.0",
    );
    assert_names(&e, "unknown_fluid_field", "fluid[0].speed", "unknown field");
}

#[test]
fn missing_field() {
    let e = err_with("missing_field", "duration = 1.0\n", "");
    assert_names(&e, "missing_field", "simulation.duration", "missing field");
}

#[test]
fn wrong_vector_length() {
    let e = err_with("vec_len", "max = [0.5, 0.5, 1.0]", "max = [0.5, 0.5]");
    assert_names(&e, "vec_len", "fluid[0].max", "invalid length 2");
}

#[test]
fn unknown_kind() {
    let e = err_with("unknown_kind", "kind = \"sphere\"", "kind = \"cone\"");
    assert_names(&e, "unknown_kind", "solid[0].kind", "unknown variant");
}

#[test]
fn negative_spacing() {
    let e = err_with(
        "neg_spacing",
        "particle_spacing = 0.05",
        "particle_spacing = -0.05",
    );
    assert_names(
        &e,
        "neg_spacing",
        "simulation.particle_spacing",
        "must be finite and > 0",
    );
}

#[test]
fn zero_duration() {
    let e = err_with("zero_duration", "duration = 1.0", "duration = 0.0");
    assert_names(
        &e,
        "zero_duration",
        "simulation.duration",
        "must be finite and > 0",
    );
}

#[test]
fn zero_frame_dt() {
    let e = err_with("zero_frame_dt", "frame_dt = 0.02", "frame_dt = 0");
    assert_names(
        &e,
        "zero_frame_dt",
        "simulation.frame_dt",
        "must be finite and > 0",
    );
}

#[test]
fn negative_radius() {
    let e = err_with("neg_radius", "radius = 0.2", "radius = -0.2");
    assert_names(
        &e,
        "neg_radius",
        "solid[0].radius",
        "must be finite and > 0",
    );
}

#[test]
fn min_not_below_max() {
    let e = err_with("min_max", "max = [0.5, 0.5, 1.0]", "max = [0.5, 0.0, 1.0]");
    assert_names(
        &e,
        "min_max",
        "fluid[0].min",
        "min must be < max on every axis (y",
    );
}

#[test]
fn tank_min_not_below_max() {
    let e = err_with(
        "tank_min_max",
        "max = [2.0, 1.0, 1.0]",
        "max = [2.0, 1.0, -1.0]",
    );
    assert_names(
        &e,
        "tank_min_max",
        "tank.min",
        "min must be < max on every axis (z",
    );
}

#[test]
fn fluid_outside_tank() {
    let e = err_with(
        "outside_tank",
        "max = [0.5, 0.5, 1.0]",
        "max = [0.5, 0.5, 1.5]",
    );
    assert_names(&e, "outside_tank", "fluid[0].max", "is not inside the tank");
}

#[test]
fn mesh_fluid_outside_tank() {
    let e = err_with(
        "mesh_outside_tank",
        "translate = [1.0, 0.5, 0.4]",
        "translate = [1.9, 0.5, 0.4]",
    );
    assert_names(
        &e,
        "mesh_outside_tank",
        "fluid[1].translate",
        "is not inside the tank",
    );
}

#[test]
fn fluid_overlapping_a_solid() {
    let e = err_with(
        "overlap",
        "center = [1.6, 0.3, 0.5]",
        "center = [0.3, 0.3, 0.5]",
    );
    assert_names(&e, "overlap", "fluid[0]", "overlaps solid[0]");
}

#[test]
fn fluid_overlapping_a_mesh_solid() {
    let e = err_with(
        "overlap_mesh",
        "translate = [0.7, 0.0, 0.0]",
        "translate = [0.4, 0.0, 0.0]",
    );
    assert_names(&e, "overlap_mesh", "fluid[0]", "overlaps solid[1]");
}

#[test]
fn zero_substeps() {
    let e = err_with("zero_substeps", "substeps = 2", "substeps = 0");
    assert_names(&e, "zero_substeps", "solver.substeps", "must be >= 1");
}

#[test]
fn zero_iterations() {
    let e = err_with("zero_iterations", "iterations = 3", "iterations = 0");
    assert_names(&e, "zero_iterations", "solver.iterations", "must be >= 1");
}

#[test]
fn missing_mesh_file() {
    let e = err_with(
        "missing_mesh",
        "path = \"cube.obj\"",
        "path = \"nothere/bunny.obj\"",
    );
    assert_names(&e, "missing_mesh", "fluid[1].path", "file not found");
    let resolved = fixture_dir("missing_mesh").join("nothere/bunny.obj");
    assert!(
        e.to_string().contains(&resolved.display().to_string()),
        "{e}"
    );
}

#[test]
fn open_mesh() {
    let text = VALID.replacen(
        "path = \"cube.obj\"\nscale = 0.2\ntranslate = [0.7",
        "path = \"open.obj\"\nscale = 0.2\ntranslate = [0.7",
        1,
    );
    assert_ne!(text, VALID);
    let dir = fixture_dir("open_mesh");
    let e = Scene::parse_str(&text, &dir.join("open_mesh.toml")).unwrap_err();
    assert_names(&e, "open_mesh", "solid[1].path", "boundary edge");
    assert!(e.to_string().contains("edge ("), "{e}");
    assert!(e.to_string().contains("open.obj"), "{e}");
}

#[test]
fn nan_and_infinite_values() {
    let e = err_with(
        "nan_gravity",
        "gravity = [0.0, -9.81, 0.0]",
        "gravity = [nan, -9.81, 0.0]",
    );
    assert_names(
        &e,
        "nan_gravity",
        "simulation.gravity",
        "component x is not finite",
    );
    let e = err_with(
        "inf_min",
        "min = [0.0, 0.0, 0.0]\nmax = [0.5",
        "min = [0.0, -inf, 0.0]\nmax = [0.5",
    );
    assert_names(&e, "inf_min", "fluid[0].min", "component y is not finite");
    let e = err_with(
        "nan_spacing",
        "particle_spacing = 0.05",
        "particle_spacing = nan",
    );
    assert_names(
        &e,
        "nan_spacing",
        "simulation.particle_spacing",
        "must be finite",
    );
    let e = err_with(
        "inf_scale",
        "scale = 0.2\ntranslate = [1.0",
        "scale = inf\ntranslate = [1.0",
    );
    assert_names(&e, "inf_scale", "fluid[1].scale", "must be finite");
}

#[test]
fn too_many_particles() {
    let e = err_with(
        "too_many",
        "particle_spacing = 0.05",
        "particle_spacing = 0.001",
    );
    assert_names(
        &e,
        "too_many",
        "fluid[0]",
        "more than the maximum of 20000000",
    );
}

#[test]
fn field_of_another_kind() {
    let e = err_with(
        "other_kind",
        "velocity = [0.0, 0.0, 0.0]",
        "normal = [0.0, 1.0, 0.0]",
    );
    assert_names(&e, "other_kind", "fluid[0].normal", "unknown field");
    let e = err_with("other_kind_r", "velocity = [0.0, 0.0, 0.0]", "radius = 1.0");
    assert_names(
        &e,
        "other_kind_r",
        "fluid[0].radius",
        "not a field of kind = \"block\"",
    );
    let e = err_with(
        "other_kind2",
        "velocity = [0.0, 0.0, 0.0]",
        "path = \"cube.obj\"",
    );
    assert_names(
        &e,
        "other_kind2",
        "fluid[0].path",
        "not a field of kind = \"block\"",
    );
}

#[test]
fn min_iterations_without_tolerance() {
    let e = err_with("min_no_tol", "xsph_c = 0.01", "min_iterations = 2");
    assert_names(
        &e,
        "min_no_tol",
        "solver.min_iterations",
        "only applies with solver.mean_compression_tolerance",
    );
}

#[test]
fn min_iterations_above_iterations() {
    let e = err_with(
        "min_above_max",
        "xsph_c = 0.01",
        "mean_compression_tolerance = 0.001\nmin_iterations = 4",
    );
    assert_names(
        &e,
        "min_above_max",
        "solver.min_iterations",
        "must be >= 1 and <= solver.iterations = 3, got 4",
    );
}

#[test]
fn non_positive_compression_tolerance() {
    let e = err_with(
        "zero_tol",
        "xsph_c = 0.01",
        "mean_compression_tolerance = 0.0",
    );
    assert_names(&e, "zero_tol", "solver.mean_compression_tolerance", "> 0");
}

#[test]
fn quick_iterations_below_min_iterations() {
    let text = VALID
        .replacen(
            "xsph_c = 0.01",
            "mean_compression_tolerance = 0.001\nmin_iterations = 2",
            1,
        )
        .replacen("duration = 0.5", "duration = 0.5\niterations = 1", 1);
    let file = fixture_dir("quick_min").join("quick_min.toml");
    let e = Scene::parse_str(&text, &file).unwrap_err();
    assert_names(
        &e,
        "quick_min",
        "quick.iterations",
        "must be >= solver.min_iterations = 2, got 1",
    );
}

#[test]
fn bad_quick_override() {
    let e = err_with(
        "bad_quick",
        "particle_spacing = 0.1",
        "particle_spacing = -0.1",
    );
    assert_names(
        &e,
        "bad_quick",
        "quick.particle_spacing",
        "must be finite and > 0",
    );
    // A quick spacing that makes a mesh fluid empty is reported as a quick-mode problem.
    let e = err_with(
        "quick_empty",
        "particle_spacing = 0.1",
        "particle_spacing = 0.3",
    );
    assert_names(
        &e,
        "quick_empty",
        "fluid[1]",
        "with the [quick] overrides: contains no particle",
    );
}

#[test]
fn bad_name() {
    let e = err_with("bad_name", "name = \"fixture\"", "name = \"../x\"");
    assert_names(&e, "bad_name", "name", "must be non-empty");
}

#[test]
fn unreadable_scene_file() {
    let dir = fixture_dir("unreadable");
    let file = dir.join("unreadable.toml");
    let e = Scene::load(&file).unwrap_err();
    assert!(matches!(e, SceneError::Read { .. }));
    assert_eq!(e.field(), "<file>");
    let msg = e.to_string();
    assert!(
        msg.contains("unreadable.toml") && msg.contains("cannot read the scene file"),
        "{msg}"
    );
}

/// A cylinder solid and a cylinder fluid parse, and the solid's distance is that of
/// `sph_core::CylinderSdf` with the file's values (after the tank, in file order).
#[test]
fn cylinder_fluid_and_solid_parse() {
    let text = VALID
        .replacen(
            "kind = \"sphere\"\ncenter = [1.6, 0.3, 0.5]\nradius = 0.2",
            "kind = \"cylinder\"\nbase_center = [1.6, 0.1, 0.5]\nradius = 0.2\nheight = 0.3",
            1,
        )
        .replacen(
            "kind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 1.0]",
            "kind = \"cylinder\"\nbase_center = [0.3, 0.0, 0.5]\nradius = 0.2\nheight = 0.4",
            1,
        );
    let dir = fixture_dir("cylinders");
    let s = Scene::parse_str(&text, &dir.join("cylinders.toml")).unwrap();
    assert!(matches!(s.solids[0], sph_scene::SolidSpec::Cylinder { .. }));
    assert!(matches!(s.fluids[0], sph_scene::FluidSpec::Cylinder { .. }));
    let solids = s.build_solids::<f64>().unwrap();
    let oracle = sph_core::CylinderSdf::new(sph_core::Vec3::new(1.6, 0.1, 0.5), 0.2, 0.3).unwrap();
    for p in [[1.6, 0.2, 0.5], [1.0, 0.0, 0.0], [1.7, 0.5, 0.6]] {
        let p = sph_core::Vec3::from(p);
        use sph_core::Sdf;
        assert_eq!(solids[1].signed_distance(&p), oracle.signed_distance(&p));
    }
    // a 4-spacing radius disc of 52 points (lattice centred on the axis), 8 layers
    assert_eq!(s.fluids[0].bounds().extent().y, 0.4);
    let n = s.fluid_positions::<f64>().unwrap().len();
    assert_eq!(n, 52 * 8 + 64);
}
