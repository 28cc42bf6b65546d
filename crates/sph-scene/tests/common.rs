//! Shared fixtures: a valid scene and small meshes in a per-test temporary directory.

#![allow(dead_code)]

use std::path::PathBuf;

use sph_scene::{Scene, SceneError};

/// A valid scene using a closed cube mesh as fluid and as solid (`cube.obj`).
pub const VALID: &str = r#"
name = "fixture"

[simulation]
precision = "f64"
particle_spacing = 0.05
duration = 1.0
frame_dt = 0.02
gravity = [0.0, -9.81, 0.0]

[solver]
kind = "pbf"
substeps = 2
iterations = 3
xsph_c = 0.01

[tank]
min = [0.0, 0.0, 0.0]
max = [2.0, 1.0, 1.0]

[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.5, 0.5, 1.0]
velocity = [0.0, 0.0, 0.0]

[[fluid]]
kind = "mesh"
path = "cube.obj"
scale = 0.2
translate = [1.0, 0.5, 0.4]

[[solid]]
kind = "sphere"
center = [1.6, 0.3, 0.5]
radius = 0.2

[[solid]]
kind = "mesh"
path = "cube.obj"
scale = 0.2
translate = [0.7, 0.0, 0.0]

[output]
every_frames = 2
vtk = false

[quick]
particle_spacing = 0.1
duration = 0.5
"#;

const CUBE_V: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n";
/// Quads, counter-clockwise seen from outside (corner c = x + 2y + 4z, 1-based).
const CUBE_F: [&str; 6] = [
    "f 1 5 7 3\n",
    "f 2 4 8 6\n",
    "f 1 2 6 5\n",
    "f 3 7 8 4\n",
    "f 1 3 4 2\n",
    "f 5 6 8 7\n",
];

/// A fresh directory holding `cube.obj` (closed) and `open.obj` (the cube without its top).
pub fn fixture_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sph-scene-test-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("cube.obj"), format!("{CUBE_V}{}", CUBE_F.concat())).unwrap();
    let open: String = CUBE_F
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != 3)
        .map(|(_, f)| *f)
        .collect();
    std::fs::write(dir.join("open.obj"), format!("{CUBE_V}{open}")).unwrap();
    dir
}

/// Parses `VALID` with `from` replaced by `to` (which must occur) and returns the error.
pub fn err_with(test: &str, from: &str, to: &str) -> SceneError {
    assert!(VALID.contains(from), "fixture lacks {from:?}");
    let text = VALID.replacen(from, to, 1);
    let dir = fixture_dir(test);
    let file = dir.join(format!("{test}.toml"));
    match Scene::parse_str(&text, &file) {
        Ok(_) => panic!("{test}: accepted"),
        Err(e) => e,
    }
}

/// The error names the file `<test>.toml`, the field path `field` (also as
/// [`SceneError::field`]) and contains `reason`.
pub fn assert_names(e: &SceneError, test: &str, field: &str, reason: &str) {
    let msg = e.to_string();
    println!("{msg}");
    assert!(msg.contains(&format!("{test}.toml")), "no file in: {msg}");
    assert!(msg.contains(field), "no field {field:?} in: {msg}");
    assert_eq!(e.field(), field, "{msg}");
    assert!(msg.contains(reason), "no reason {reason:?} in: {msg}");
}
