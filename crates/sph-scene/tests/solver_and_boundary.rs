//! The `[solver]` table (one variant per solver kind, the other kinds' fields refused with
//! path and line) and the `[boundary]` table.

mod common;

use common::{assert_names, err_with, fixture_dir, VALID};
use sph_scene::{BoundaryModel, BoundarySpec, InitialMasses, Scene, SolverKind, SolverSpec};

/// Line 12 of `VALID` is `kind = "pbf"`, line 15 `xsph_c = 0.01`.
const KIND_LINE: &str = "(line 12, column 8)";
/// The line of the `xsph_c` field the tests replace (an unknown field of a variant is named
/// by its line: serde reads the flattened settings from a buffer without positions).
const XSPH_LINE: &str = "(line 15)";

fn parse(test: &str, text: &str) -> Scene {
    let file = fixture_dir(test).join(format!("{test}.toml"));
    Scene::parse_str(text, &file).unwrap_or_else(|e| panic!("{e}"))
}

/// `VALID` as a PCISPH scene (`xsph_c` kept).
fn pcisph() -> String {
    VALID.replacen("kind = \"pbf\"", "kind = \"pcisph\"", 1)
}

#[test]
fn pbf_fixture_reads_into_the_pbf_variant() {
    let s = parse("pbf_variant", VALID);
    assert_eq!(s.solver.kind(), SolverKind::Pbf);
    assert_eq!(s.solver.kind_name(), "pbf");
    let SolverSpec::Pbf(p) = &s.solver else {
        panic!("{:?}", s.solver)
    };
    assert_eq!(
        (p.common.substeps, p.solver_iterations, p.xsph_c),
        (2, 3, Some(0.01))
    );
    assert_eq!(p.scorr_k, None);
}

#[test]
fn pcisph_scene_with_its_own_options() {
    let text = pcisph().replacen(
        "xsph_c = 0.01",
        "xsph_c = 0.01\nclamp_negative_pressure = true\ndensity_error_tolerance = 0.01\nrest_density = 998.0",
        1,
    );
    let s = parse("pcisph_variant", &text);
    assert_eq!(s.solver.kind_name(), "pcisph");
    let SolverSpec::Pcisph(p) = &s.solver else {
        panic!("{:?}", s.solver)
    };
    assert_eq!(p.clamp_negative_pressure, Some(true));
    assert_eq!(p.density_error_tolerance, Some(0.01));
    assert_eq!(s.solver.common().rest_density, Some(998.0));
    assert_eq!(s.solver.common().support_over_spacing, None);
    // The [quick] overrides reach the variant.
    let text = text.replacen(
        "duration = 0.5",
        "duration = 0.5\nsubsteps = 1\niterations = 7",
        1,
    );
    let q = parse("pcisph_quick", &text).quick();
    assert_eq!((q.solver.substeps(), q.solver.iterations()), (1, 7));
}

#[test]
fn pbf_field_under_pcisph_is_refused_with_path_and_line() {
    for field in [
        "vorticity_epsilon = 0.1",
        "scorr_k = 0.1",
        "min_iterations = 2",
    ] {
        let name = field.split(' ').next().unwrap();
        let text = pcisph().replacen("xsph_c = 0.01", field, 1);
        let file = fixture_dir("pbf_only").join("pbf_only.toml");
        let e = Scene::parse_str(&text, &file).unwrap_err();
        assert_names(&e, "pbf_only", &format!("solver.{name}"), "unknown field");
        let msg = e.to_string();
        assert!(msg.contains(XSPH_LINE), "no line in: {msg}");
        assert!(msg.contains("kind = \"pcisph\" has no such field"), "{msg}");
    }
}

#[test]
fn pcisph_field_under_pbf_is_refused_with_path_and_line() {
    for field in [
        "density_error_tolerance = 0.01",
        "clamp_negative_pressure = true",
    ] {
        let name = field.split(' ').next().unwrap();
        let e = err_with("pcisph_only", "xsph_c = 0.01", field);
        assert_names(
            &e,
            "pcisph_only",
            &format!("solver.{name}"),
            "unknown field",
        );
        let msg = e.to_string();
        assert!(msg.contains(XSPH_LINE), "no line in: {msg}");
        assert!(msg.contains("kind = \"pbf\" has no such field"), "{msg}");
    }
}

#[test]
fn missing_field_of_a_flattened_part_is_not_called_unknown() {
    let shipped = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/granular_repose_thesis_30.toml"
    ))
    .unwrap();
    let text = shipped.replacen("substeps = 16", "", 1);
    assert_ne!(text, shipped, "the shipped scene sets substeps");
    let file = fixture_dir("no_substeps").join("no_substeps.toml");
    let e = Scene::parse_str(&text, &file).unwrap_err();
    assert_names(
        &e,
        "no_substeps",
        "solver.substeps",
        "missing field `substeps`",
    );
    let msg = e.to_string();
    assert!(!msg.contains("has no such field"), "{msg}");
}

#[test]
fn unknown_solver_kind_names_the_allowed_kinds() {
    let e = err_with("bad_solver_kind", "kind = \"pbf\"", "kind = \"sph\"");
    assert_names(
        &e,
        "bad_solver_kind",
        "solver.kind",
        "unknown variant `sph`, expected one of `pbf`, `pcisph`, `iisph`, `granular`",
    );
    assert!(e.to_string().contains(KIND_LINE), "{e}");
}

#[test]
fn missing_solver_kind() {
    let e = err_with("no_solver_kind", "kind = \"pbf\"\n", "");
    assert_names(&e, "no_solver_kind", "solver.kind", "missing field `kind`");
}

#[test]
fn wrong_type_in_a_variant_keeps_path_and_line() {
    let e = err_with("pcisph_type", "xsph_c = 0.01", "xsph_c = \"a lot\"");
    assert_names(&e, "pcisph_type", "solver.xsph_c", "invalid type");
    assert!(e.to_string().contains("(line 15, column 10)"), "{e}");
}

#[test]
fn pcisph_value_checks() {
    for (line, field, reason) in [
        (
            "xsph_c = 1.5",
            "solver.xsph_c",
            "must be in [0, 1], got 1.5",
        ),
        (
            "density_error_tolerance = 0.0",
            "solver.density_error_tolerance",
            "> 0",
        ),
        (
            "support_over_spacing = 1.0",
            "solver.support_over_spacing",
            "> 1",
        ),
    ] {
        let text = pcisph().replacen("xsph_c = 0.01", line, 1);
        let file = fixture_dir("pcisph_values").join("pcisph_values.toml");
        let e = Scene::parse_str(&text, &file).unwrap_err();
        assert_names(&e, "pcisph_values", field, reason);
    }
    let e = err_with(
        "pcisph_zero",
        "kind = \"pbf\"\nsubsteps = 2",
        "kind = \"pcisph\"\nsubsteps = 0",
    );
    assert_names(&e, "pcisph_zero", "solver.substeps", "must be >= 1, got 0");
}

#[test]
fn solver_spec_deserializes_as_an_internally_tagged_table() {
    let s: SolverSpec =
        toml::from_str("kind = \"pcisph\"\nsubsteps = 1\niterations = 2\nxsph_c = 0.5").unwrap();
    let SolverSpec::Pcisph(p) = &s else {
        panic!("{s:?}")
    };
    assert_eq!(
        (p.common.substeps, p.pressure_iterations, p.xsph_c),
        (1, 2, Some(0.5))
    );
    let e = toml::from_str::<SolverSpec>(
        "kind = \"pcisph\"\nsubsteps = 1\niterations = 2\nscorr_k = 0.1",
    )
    .unwrap_err();
    assert!(e.to_string().contains("unknown field `scorr_k`"), "{e}");
    let e =
        toml::from_str::<SolverSpec>("kind = \"sph\"\nsubsteps = 1\niterations = 2").unwrap_err();
    assert!(e.to_string().contains("unknown variant `sph`"), "{e}");
}

#[test]
fn with_kind_keeps_the_shared_settings() {
    let text = VALID.replacen(
        "xsph_c = 0.01",
        "xsph_c = 0.01\nvorticity_epsilon = 0.1\nrest_density = 990.0",
        1,
    );
    let s = parse("with_kind", &text);
    assert_eq!(s.solver.with_kind(SolverKind::Pbf), s.solver);
    let c = s.solver.with_kind(SolverKind::Pcisph);
    let SolverSpec::Pcisph(p) = &c else {
        panic!("{c:?}")
    };
    assert_eq!((p.common.substeps, p.pressure_iterations), (2, 3));
    assert_eq!(
        (p.xsph_c, p.common.rest_density, p.clamp_negative_pressure),
        (Some(0.01), Some(990.0), None)
    );
    let back = c.with_kind(SolverKind::Pbf);
    let SolverSpec::Pbf(b) = &back else {
        panic!("{back:?}")
    };
    // PBF's own option did not survive the round trip through PCISPH.
    assert_eq!(
        (b.vorticity_epsilon, b.common.rest_density),
        (None, Some(990.0))
    );
}

#[test]
fn boundary_model_values() {
    let absent = parse("boundary_absent", VALID);
    assert_eq!(absent.boundary, BoundarySpec::default());
    assert_eq!(absent.boundary.model, BoundaryModel::VolumeMap);
    assert_eq!(BoundaryModel::default(), BoundaryModel::VolumeMap);
    for (value, model) in [
        ("volume-map", BoundaryModel::VolumeMap),
        ("collision", BoundaryModel::Collision),
    ] {
        let text = format!("{VALID}\n[boundary]\nmodel = \"{value}\"\n");
        assert_eq!(parse("boundary_model", &text).boundary.model, model);
    }
    // An empty table takes the default model.
    let text = format!("{VALID}\n[boundary]\n");
    assert_eq!(
        parse("boundary_empty", &text).boundary.model,
        BoundaryModel::default()
    );
}

#[test]
fn initial_masses_values() {
    let absent = parse("masses_absent", VALID);
    assert_eq!(absent.boundary.initial_masses, InitialMasses::Lattice);
    for (value, masses) in [
        ("lattice", InitialMasses::Lattice),
        ("calibrated", InitialMasses::Calibrated),
    ] {
        let text = format!("{VALID}\n[boundary]\ninitial_masses = \"{value}\"\n");
        let s = parse("initial_masses", &text);
        assert_eq!(s.boundary.initial_masses, masses);
        assert_eq!(s.boundary.model, BoundaryModel::default());
    }
    let file = fixture_dir("bad_masses").join("bad_masses.toml");
    let text = format!("{VALID}\n[boundary]\ninitial_masses = \"calibrate\"\n");
    let e = Scene::parse_str(&text, &file).unwrap_err();
    assert_names(
        &e,
        "bad_masses",
        "boundary.initial_masses",
        "unknown variant `calibrate`, expected `lattice` or `calibrated`",
    );
}

#[test]
fn bad_boundary_model_lists_the_allowed_values() {
    let file = fixture_dir("bad_boundary").join("bad_boundary.toml");
    let lines = VALID.lines().count();
    let text = format!("{VALID}\n[boundary]\nmodel = \"volume_map\"\n");
    let e = Scene::parse_str(&text, &file).unwrap_err();
    assert_names(
        &e,
        "bad_boundary",
        "boundary.model",
        "unknown variant `volume_map`, expected one of `volume-map`, `collision`, `particles`",
    );
    let line = format!("(line {}, column 9)", lines + 3);
    assert!(e.to_string().contains(&line), "no {line} in: {e}");
}

#[test]
fn unknown_boundary_field() {
    let file = fixture_dir("boundary_field").join("boundary_field.toml");
    let text = format!("{VALID}\n[boundary]\nmodel = \"collision\"\nfriction = 0.3\n");
    let e = Scene::parse_str(&text, &file).unwrap_err();
    assert_names(
        &e,
        "boundary_field",
        "boundary.friction",
        "unknown field `friction`",
    );
}

#[test]
fn solver_must_be_a_table() {
    // serde reads a struct from an array too; the parser insists on a table.
    let text = VALID
        .replacen(
            "[solver]\nkind = \"pbf\"\nsubsteps = 2\niterations = 3\nxsph_c = 0.01\n",
            "",
            1,
        )
        .replacen(
            "name = \"fixture\"\n",
            "name = \"fixture\"\nsolver = [\"pbf\", 2, 3]\n",
            1,
        );
    assert!(!text.contains("[solver]"));
    let file = fixture_dir("solver_array").join("solver_array.toml");
    let e = Scene::parse_str(&text, &file).unwrap_err();
    assert_names(&e, "solver_array", "solver", "must be a table, not array");
}

/// Every key renamed to its parameter's name (`SolverKind::renamed`) still loads under its
/// old name, into the same settings; and a renamed key is refused where the kind has none.
#[test]
fn old_keys_still_load() {
    // A table of each kind giving every renamed key under its new name.
    let table = |kind: SolverKind| -> String {
        let mut t = format!("kind = \"{}\"\nsubsteps = 2\n", kind.name());
        if kind == SolverKind::Granular || kind == SolverKind::Elastoplastic {
            t.push_str("friction_angle_deg = 30.0\n");
        }
        if kind == SolverKind::Pbf {
            t.push_str("mean_compression_tolerance = 0.01\n");
        }
        for (k, (_, new)) in kind.renamed().iter().enumerate() {
            t.push_str(&format!("{new} = {}\n", 3 - k));
        }
        t
    };
    let mut renamed = 0;
    for &kind in SolverKind::ALL {
        let new = table(kind);
        let spec: SolverSpec = toml::from_str(&new).unwrap();
        for (old_key, new_key) in kind.renamed() {
            let old = new.replacen(&format!("{new_key} ="), &format!("{old_key} ="), 1);
            assert_ne!(old, new);
            let from_old: SolverSpec = toml::from_str(&old).unwrap();
            assert_eq!(from_old, spec, "{} {old_key}", kind.name());
            renamed += 1;
        }
    }
    // PBF: iterations, min_iterations; PCISPH: iterations.
    assert_eq!(renamed, 3);
    // Shipped-style scene text with the old key reads as with the new one.
    let old = parse("old_keys", VALID);
    let new = parse(
        "old_keys",
        &VALID.replacen("iterations = 3", "solver_iterations = 3", 1),
    );
    assert_eq!(old.solver, new.solver);
}
