//! Overrides of a scene's keys by dotted path: applied to the document before serde reads
//! it, so that they are checked as the file's own values, at the same field path.

mod common;

use common::{fixture_dir, VALID};
use sph_scene::{FluidSpec, Override, Scene, SceneError, SolverSpec};

fn with(test: &str, overrides: &[(&str, toml::Value)]) -> Result<Scene, SceneError> {
    let file = fixture_dir(test).join(format!("{test}.toml"));
    let o: Vec<Override> = overrides
        .iter()
        .map(|(p, v)| Override::new(*p, v.clone()))
        .collect();
    Scene::parse_str_with(VALID, &file, &o)
}

fn refused(test: &str, overrides: &[(&str, toml::Value)]) -> SceneError {
    match with(test, overrides) {
        Ok(_) => panic!("{test}: accepted"),
        Err(e) => e,
    }
}

/// The scene `VALID` with `from` replaced by `to` in its text: what an edited file gives.
fn edited(test: &str, from: &str, to: &str) -> Scene {
    assert!(VALID.contains(from), "fixture lacks {from:?}");
    let file = fixture_dir(test).join(format!("{test}.toml"));
    Scene::parse_str(&VALID.replacen(from, to, 1), &file).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn an_override_gives_the_scene_of_the_edited_file() {
    let o = with(
        "ov_same",
        &[
            ("simulation.duration", toml::Value::Float(0.5)),
            ("solver.substeps", toml::Value::Integer(4)),
            ("solver.scorr_k", toml::Value::Float(0.2)), // a key the file does not write
            (
                "fluid[0].max",
                toml::Value::Array(vec![0.4.into(), 0.5.into(), 1.0.into()]),
            ),
        ],
    )
    .unwrap();
    let e = edited("ov_same_edit", "duration = 1.0", "duration = 0.5");
    assert_eq!(o.duration_s, e.duration_s);
    assert_eq!(o.frame_count(), 25);
    let SolverSpec::Pbf(p) = &o.solver else {
        panic!("{:?}", o.solver)
    };
    assert_eq!((p.common.substeps, p.scorr_k), (4, Some(0.2)));
    let FluidSpec::Block { max, .. } = o.fluids[0] else {
        panic!("{:?}", o.fluids[0])
    };
    assert_eq!(max, [0.4, 0.5, 1.0]);
    // The other values are the file's.
    assert_eq!(o.frame_dt_s, 0.02);
    assert_eq!(o.fluids.len(), 2);
}

#[test]
fn later_overrides_win_and_integers_set_reals() {
    let o = with(
        "ov_order",
        &[
            ("simulation.duration", toml::Value::Float(0.5)),
            ("simulation.duration", toml::Value::Integer(2)),
        ],
    )
    .unwrap();
    assert_eq!(o.duration_s, 2.0);
}

#[test]
fn a_value_of_the_wrong_type_is_refused_at_its_key() {
    let e = refused(
        "ov_type",
        &[("solver.substeps", toml::Value::String("eight".into()))],
    );
    assert_eq!(e.field(), "solver.substeps", "{e}");
    let msg = e.to_string();
    assert!(msg.contains("given as an override"), "{msg}");
    assert!(
        !msg.contains("line"),
        "an override has no line in the file: {msg}"
    );
}

#[test]
fn an_out_of_range_value_is_refused_at_its_key() {
    let e = refused(
        "ov_range",
        &[("simulation.particle_spacing", toml::Value::Float(-0.05))],
    );
    assert_eq!(e.field(), "simulation.particle_spacing", "{e}");
    let msg = e.to_string();
    assert!(msg.contains("given as an override"), "{msg}");
    assert!(msg.contains("-0.05"), "{msg}");
}

#[test]
fn an_unknown_key_is_refused_with_the_keys_of_its_table() {
    let e = refused(
        "ov_unknown",
        &[("simulation.durration", toml::Value::Float(1.0))],
    );
    assert_eq!(e.field(), "simulation.durration", "{e}");
    let msg = e.to_string();
    for known in ["particle_spacing", "duration", "frame_dt", "gravity"] {
        assert!(msg.contains(&format!("`{known}`")), "{msg}");
    }
    let e = refused(
        "ov_unknown_solver",
        &[("solver.friction_angle_deg", toml::Value::Float(30.0))],
    );
    assert_eq!(e.field(), "solver.friction_angle_deg", "{e}");
    assert!(
        e.to_string().contains("kind = \"pbf\" has no such field"),
        "{e}"
    );
    let e = refused(
        "ov_unknown_table",
        &[("solvr.substeps", toml::Value::Integer(2))],
    );
    assert_eq!(e.field(), "solvr", "{e}");
    assert!(e.to_string().contains("`simulation`"), "{e}");
}

#[test]
fn paths_that_do_not_fit_the_document_are_refused_by_name() {
    let e = refused("ov_index", &[("fluid[2].min", toml::Value::Float(1.0))]);
    assert_eq!(e.field(), "fluid[2]", "{e}");
    assert!(e.to_string().contains("2 elements of `fluid`"), "{e}");
    let e = refused(
        "ov_scalar",
        &[("simulation.duration.x", toml::Value::Float(1.0))],
    );
    assert_eq!(e.field(), "simulation.duration", "{e}");
    assert!(e.to_string().contains("not a table"), "{e}");
    let e = refused(
        "ov_syntax",
        &[("simulation..duration", toml::Value::Float(1.0))],
    );
    assert!(e.to_string().contains("not a key"), "{e}");
}

#[test]
fn errors_of_the_file_keep_their_lines() {
    // An override elsewhere does not move the file's lines: line 8 is `frame_dt`.
    let file = fixture_dir("ov_lines").join("ov_lines.toml");
    let text = VALID.replacen("frame_dt = 0.02", "frame_dt = -0.02", 1);
    let o = [Override::new("solver.scorr_k", toml::Value::Float(0.2))];
    let e = Scene::parse_str_with(&text, &file, &o).unwrap_err();
    assert_eq!(e.field(), "simulation.frame_dt", "{e}");
    assert!(e.to_string().contains("(line 8)"), "{e}");
}

#[test]
fn an_upscaling_factor_beyond_the_passive_point_bound_is_refused_before_any_allocation() {
    let text = r#"
name = "column"
[simulation]
particle_spacing = 0.01
duration = 0.1
frame_dt = 0.02
[solver]
kind = "granular"
substeps = 8
friction_angle_deg = 30.0
[tank]
min = [0.0, 0.0, 0.0]
max = [0.5, 0.5, 0.5]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.2, 0.3, 0.2]
"#;
    let file = fixture_dir("ov_upscaling").join("column.toml");
    // 20 x 30 x 20 = 12,000 particles: 8 passive points each are allowed, 4096 are not
    // (49 M points, more than MAX_PASSIVE_POINTS).
    let ok = [Override::new(
        "solver.upscaling_factor",
        toml::Value::Integer(8),
    )];
    Scene::parse_str_with(text, &file, &ok).unwrap_or_else(|e| panic!("{e}"));
    let big = [Override::new(
        "solver.upscaling_factor",
        toml::Value::Integer(4096),
    )];
    let e = Scene::parse_str_with(text, &file, &big).unwrap_err();
    assert_eq!(e.field(), "solver.upscaling_factor", "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("MAX_PASSIVE_POINTS") && msg.contains("4096"),
        "{msg}"
    );
    assert_eq!(sph_scene::MAX_PASSIVE_POINTS, 20_000_000);
}
