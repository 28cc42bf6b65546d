//! The full message of every kind of malformed scene and mesh, as reviewed snapshots
//! (`tests/snapshots/error_snapshots__<case>.snap`), so that a message cannot silently get
//! worse. One table row per case: an edit of the valid fixture scene (or a mesh file written
//! beside it) and the snapshot name. The temporary directory in messages reads `<dir>`.
//!
//! A new case fails until its snapshot is reviewed and committed: run once with
//! `INSTA_UPDATE=always`, read the new `.snap` files, commit them. The final check runs with
//! `INSTA_UPDATE=no`, so a missing or changed snapshot fails.

mod common;

use common::{fixture_dir, VALID};
use sph_scene::Scene;

/// A malformed scene: `VALID` with each `(from, to)` replaced once (each `from` must occur).
struct SceneCase {
    name: &'static str,
    edits: &'static [(&'static str, &'static str)],
}

const SCENE_CASES: &[SceneCase] = &[
    SceneCase {
        name: "toml_syntax",
        edits: &[("substeps = 2", "substeps = = 2")],
    },
    SceneCase {
        name: "wrong_type",
        edits: &[("substeps = 2", "substeps = \"two\"")],
    },
    SceneCase {
        name: "negative_integer",
        edits: &[("iterations = 3", "iterations = -3")],
    },
    SceneCase {
        name: "unknown_field",
        edits: &[("xsph_c = 0.01", "xsph = 0.01")],
    },
    SceneCase {
        name: "missing_field",
        edits: &[("duration = 1.0\n", "")],
    },
    SceneCase {
        name: "missing_solver",
        edits: &[(
            "[solver]\nkind = \"pbf\"\nsubsteps = 2\niterations = 3\nxsph_c = 0.01\n",
            "",
        )],
    },
    SceneCase {
        name: "unknown_solver_kind",
        edits: &[("kind = \"pbf\"", "kind = \"flip\"")],
    },
    SceneCase {
        name: "vector_length",
        edits: &[("max = [0.5, 0.5, 1.0]", "max = [0.5, 0.5]")],
    },
    SceneCase {
        name: "unknown_solid_kind",
        edits: &[("kind = \"sphere\"", "kind = \"cone\"")],
    },
    SceneCase {
        name: "negative_spacing",
        edits: &[("particle_spacing = 0.05", "particle_spacing = -0.05")],
    },
    SceneCase {
        name: "zero_spacing",
        edits: &[("particle_spacing = 0.05", "particle_spacing = 0.0")],
    },
    SceneCase {
        name: "nan_spacing",
        edits: &[("particle_spacing = 0.05", "particle_spacing = nan")],
    },
    SceneCase {
        name: "zero_duration",
        edits: &[("duration = 1.0", "duration = 0.0")],
    },
    SceneCase {
        name: "zero_frame_dt",
        edits: &[("frame_dt = 0.02", "frame_dt = 0")],
    },
    SceneCase {
        name: "frame_dt_1e30",
        edits: &[("frame_dt = 0.02", "frame_dt = 1e30")],
    },
    SceneCase {
        name: "frame_dt_too_long_for_substeps",
        edits: &[("frame_dt = 0.02", "frame_dt = 0.5")],
    },
    SceneCase {
        name: "initial_velocity_too_fast_for_step",
        edits: &[("velocity = [0.0, 0.0, 0.0]", "velocity = [0.0, -20.0, 0.0]")],
    },
    SceneCase {
        name: "too_many_substeps",
        edits: &[("substeps = 2", "substeps = 100000000")],
    },
    SceneCase {
        name: "zero_substeps",
        edits: &[("substeps = 2", "substeps = 0")],
    },
    SceneCase {
        name: "too_many_frames",
        edits: &[("duration = 1.0", "duration = 1e9")],
    },
    SceneCase {
        name: "nan_gravity",
        edits: &[("gravity = [0.0, -9.81, 0.0]", "gravity = [nan, -9.81, 0.0]")],
    },
    SceneCase {
        name: "infinite_gravity",
        edits: &[("gravity = [0.0, -9.81, 0.0]", "gravity = [0.0, -inf, 0.0]")],
    },
    SceneCase {
        name: "nan_velocity",
        edits: &[("velocity = [0.0, 0.0, 0.0]", "velocity = [0.0, nan, 0.0]")],
    },
    SceneCase {
        name: "infinite_min",
        edits: &[(
            "min = [0.0, 0.0, 0.0]\nmax = [0.5",
            "min = [0.0, -inf, 0.0]\nmax = [0.5",
        )],
    },
    SceneCase {
        name: "fluid_min_not_below_max",
        edits: &[("max = [0.5, 0.5, 1.0]", "max = [0.5, 0.0, 1.0]")],
    },
    SceneCase {
        name: "empty_fluid_block",
        edits: &[("max = [0.5, 0.5, 1.0]", "max = [0.5, 0.5, 0.01]")],
    },
    SceneCase {
        name: "fluid_outside_tank",
        edits: &[("max = [0.5, 0.5, 1.0]", "max = [0.5, 0.5, 1.5]")],
    },
    SceneCase {
        name: "mesh_fluid_outside_tank",
        edits: &[("translate = [1.0, 0.5, 0.4]", "translate = [1.9, 0.5, 0.4]")],
    },
    SceneCase {
        name: "tank_min_not_below_max",
        edits: &[("max = [2.0, 1.0, 1.0]", "max = [2.0, 1.0, -1.0]")],
    },
    SceneCase {
        name: "fluid_overlaps_solid",
        edits: &[("center = [1.6, 0.3, 0.5]", "center = [0.3, 0.3, 0.5]")],
    },
    SceneCase {
        name: "negative_radius",
        edits: &[("radius = 0.2", "radius = -0.2")],
    },
    SceneCase {
        name: "zero_plane_normal",
        edits: &[(
            "kind = \"sphere\"\ncenter = [1.6, 0.3, 0.5]\nradius = 0.2",
            "kind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 0.0]",
        )],
    },
    SceneCase {
        name: "field_of_another_kind",
        edits: &[("velocity = [0.0, 0.0, 0.0]", "path = \"cube.obj\"")],
    },
    SceneCase {
        name: "missing_mesh_file",
        edits: &[("path = \"cube.obj\"", "path = \"nothere/bunny.obj\"")],
    },
    SceneCase {
        name: "mesh_path_is_a_directory",
        edits: &[("path = \"cube.obj\"", "path = \".\"")],
    },
    SceneCase {
        name: "zero_scale",
        edits: &[(
            "scale = 0.2\ntranslate = [1.0",
            "scale = 0.0\ntranslate = [1.0",
        )],
    },
    SceneCase {
        name: "infinite_scale",
        edits: &[(
            "scale = 0.2\ntranslate = [1.0",
            "scale = inf\ntranslate = [1.0",
        )],
    },
    SceneCase {
        name: "fit_and_scale",
        edits: &[(
            "scale = 0.2\ntranslate = [1.0, 0.5, 0.4]",
            "scale = 0.2\nfit = { min = [1.0, 0.5, 0.4], max = [1.2, 0.7, 0.6] }",
        )],
    },
    SceneCase {
        name: "zero_sdf_cell",
        edits: &[(
            "translate = [0.7, 0.0, 0.0]",
            "translate = [0.7, 0.0, 0.0]\nsdf_cell = 0.0",
        )],
    },
    SceneCase {
        name: "too_many_particles",
        edits: &[("particle_spacing = 0.05", "particle_spacing = 0.001")],
    },
    SceneCase {
        name: "zero_every_frames",
        edits: &[("every_frames = 2", "every_frames = 0")],
    },
    SceneCase {
        name: "bad_name",
        edits: &[("name = \"fixture\"", "name = \"../x\"")],
    },
    SceneCase {
        name: "support_ratio_not_above_one",
        edits: &[("xsph_c = 0.01", "support_over_spacing = 1.0")],
    },
    SceneCase {
        name: "xsph_out_of_range",
        edits: &[("xsph_c = 0.01", "xsph_c = 2.0")],
    },
    SceneCase {
        name: "min_iterations_without_tolerance",
        edits: &[("xsph_c = 0.01", "min_iterations = 2")],
    },
    SceneCase {
        name: "quick_negative_spacing",
        edits: &[("particle_spacing = 0.1", "particle_spacing = -0.1")],
    },
    SceneCase {
        name: "quick_empty_fluid",
        edits: &[("particle_spacing = 0.1", "particle_spacing = 0.3")],
    },
    SceneCase {
        name: "quick_too_many_substeps",
        edits: &[("duration = 0.5", "duration = 0.5\nsubsteps = 1000000")],
    },
    SceneCase {
        name: "quick_frame_dt_too_long",
        edits: &[("duration = 0.5", "duration = 0.5\nframe_dt = 0.5")],
    },
    SceneCase {
        name: "iisph_tolerance_below_f32",
        edits: &[
            ("precision = \"f64\"", "precision = \"f32\""),
            (
                "kind = \"pbf\"\nsubsteps = 2\niterations = 3\nxsph_c = 0.01",
                "kind = \"iisph\"\nsubsteps = 2\ndensity_error_tolerance = 1e-300",
            ),
        ],
    },
    SceneCase {
        name: "friction_angle_out_of_range",
        edits: &[(
            "kind = \"pbf\"\nsubsteps = 2\niterations = 3\nxsph_c = 0.01",
            "kind = \"granular\"\nsubsteps = 2\nfriction_angle_deg = 95.0",
        )],
    },
    SceneCase {
        name: "unknown_cone_match",
        edits: &[(
            "kind = \"pbf\"\nsubsteps = 2\niterations = 3\nxsph_c = 0.01",
            "kind = \"granular\"\nsubsteps = 2\nfriction_angle_deg = 30.0\ncone_match = \"coulomb\"",
        )],
    },
    SceneCase {
        name: "iisph_unknown_field",
        edits: &[(
            "kind = \"pbf\"\nsubsteps = 2\niterations = 3\nxsph_c = 0.01",
            "kind = \"iisph\"\nsubsteps = 2\niterations = 3",
        )],
    },
    SceneCase {
        name: "wrong_type_in_iisph_settings",
        edits: &[(
            "kind = \"pbf\"\nsubsteps = 2\niterations = 3\nxsph_c = 0.01",
            "kind = \"iisph\"\nsubsteps = 2\nrelaxation = \"half\"",
        )],
    },
    SceneCase {
        name: "render_zero_size",
        edits: &[(
            "vtk = false\n",
            "vtk = false\n\n[render]\nwidth = 0\nheight = 0\n",
        )],
    },
    SceneCase {
        name: "render_too_large",
        edits: &[(
            "vtk = false\n",
            "vtk = false\n\n[render]\nwidth = 100000\nheight = 100000\n",
        )],
    },
    SceneCase {
        name: "render_unknown_field",
        edits: &[(
            "vtk = false\n",
            "vtk = false\n\n[render.camera]\nfov = 40.0\n",
        )],
    },
    SceneCase {
        name: "render_eye_at_target",
        edits: &[(
            "vtk = false\n",
            "vtk = false\n\n[render.camera]\neye = [1.0, 0.5, 0.5]\ntarget = [1.0, 0.5, 0.5]\n",
        )],
    },
    SceneCase {
        name: "cylinder_negative_radius",
        edits: &[(
            "kind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 1.0]",
            "kind = \"cylinder\"\nbase_center = [0.3, 0.0, 0.5]\nradius = -0.2\nheight = 0.4",
        )],
    },
    SceneCase {
        name: "cylinder_zero_height",
        edits: &[(
            "kind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 1.0]",
            "kind = \"cylinder\"\nbase_center = [0.3, 0.0, 0.5]\nradius = 0.2\nheight = 0.0",
        )],
    },
    SceneCase {
        name: "cylinder_thinner_than_spacing",
        edits: &[(
            "kind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 1.0]",
            "kind = \"cylinder\"\nbase_center = [0.3, 0.0, 0.5]\nradius = 0.2\nheight = 0.01",
        )],
    },
    SceneCase {
        name: "cylinder_missing_height",
        edits: &[(
            "kind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 1.0]",
            "kind = \"cylinder\"\nbase_center = [0.3, 0.0, 0.5]\nradius = 0.2",
        )],
    },
    SceneCase {
        name: "cylinder_with_block_field",
        edits: &[(
            "kind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 1.0]",
            "kind = \"cylinder\"\nbase_center = [0.3, 0.0, 0.5]\nradius = 0.2\nheight = 0.4\nmin = [0.0, 0.0, 0.0]",
        )],
    },
    SceneCase {
        name: "cylinder_outside_tank",
        edits: &[(
            "kind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 1.0]",
            "kind = \"cylinder\"\nbase_center = [0.1, 0.0, 0.5]\nradius = 0.2\nheight = 0.4",
        )],
    },
    SceneCase {
        name: "cylinder_radius_below_spacing",
        edits: &[(
            "kind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.5, 0.5, 1.0]",
            "kind = \"cylinder\"\nbase_center = [0.3, 0.0, 0.5]\nradius = 0.02\nheight = 0.4",
        )],
    },
    SceneCase {
        name: "solid_cylinder_negative_height",
        edits: &[(
            "kind = \"sphere\"\ncenter = [1.6, 0.3, 0.5]\nradius = 0.2",
            "kind = \"cylinder\"\nbase_center = [1.6, 0.1, 0.5]\nradius = 0.2\nheight = -0.3",
        )],
    },
    SceneCase {
        name: "solid_cylinder_with_center",
        edits: &[(
            "kind = \"sphere\"\ncenter = [1.6, 0.3, 0.5]\nradius = 0.2",
            "kind = \"cylinder\"\ncenter = [1.6, 0.1, 0.5]\nradius = 0.2\nheight = 0.3",
        )],
    },
    SceneCase {
        name: "fluid_overlaps_solid_cylinder",
        edits: &[(
            "kind = \"sphere\"\ncenter = [1.6, 0.3, 0.5]\nradius = 0.2",
            "kind = \"cylinder\"\nbase_center = [0.4, 0.0, 0.5]\nradius = 0.2\nheight = 0.3",
        )],
    },
    SceneCase {
        name: "render_negative_radius",
        edits: &[(
            "vtk = false\n",
            "vtk = false\n\n[render]\nparticle_radius = -1.0\n",
        )],
    },
];

/// A mesh file that replaces `cube.obj` (used as fluid and as solid by the fixture).
struct MeshCase {
    name: &'static str,
    obj: &'static str,
}

const CUBE_V: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n";

const MESH_CASES: &[MeshCase] = &[
    MeshCase {
        name: "obj_empty_file",
        obj: "",
    },
    MeshCase {
        name: "obj_cut_after_vertices",
        obj: CUBE_V,
    },
    MeshCase {
        name: "obj_corrupt_coordinate",
        obj: "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1.0.0 0\nf 1 2 3\n",
    },
    MeshCase {
        name: "obj_missing_coordinate",
        obj: "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
    },
    MeshCase {
        name: "obj_nan_coordinate",
        obj: "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n",
    },
    MeshCase {
        name: "obj_face_index_out_of_range",
        obj: "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
    },
    MeshCase {
        name: "obj_face_index_zero",
        obj: "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
    },
    MeshCase {
        name: "obj_face_index_not_a_number",
        obj: "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 three\n",
    },
    MeshCase {
        name: "obj_face_with_two_corners",
        obj: "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
    },
    MeshCase {
        name: "obj_degenerate_face",
        obj: "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2\n",
    },
    MeshCase {
        name: "obj_open_mesh",
        obj: "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
              f 1 5 7 3\nf 2 4 8 6\nf 1 2 6 5\nf 1 3 4 2\nf 5 6 8 7\n",
    },
    MeshCase {
        name: "obj_inconsistent_orientation",
        obj: "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
              f 1 5 7 3\nf 2 4 8 6\nf 1 2 6 5\nf 3 7 8 4\nf 1 3 4 2\nf 5 7 8 6\n",
    },
    MeshCase {
        name: "obj_binary_garbage",
        obj: "v 0 0 0\n\u{0}\u{1}PK\u{3}\u{4}",
    },
];

/// The error message with the test's directory replaced by `<dir>`.
fn message(e: &sph_scene::SceneError, dir: &std::path::Path) -> String {
    e.to_string().replace(&dir.display().to_string(), "<dir>")
}

#[test]
fn scene_error_messages() {
    for case in SCENE_CASES {
        let mut text = VALID.to_string();
        for (from, to) in case.edits {
            assert!(text.contains(from), "{}: fixture lacks {from:?}", case.name);
            text = text.replacen(from, to, 1);
        }
        let dir = fixture_dir(&format!("snap-{}", case.name));
        let file = dir.join("scene.toml");
        let e = match Scene::parse_str(&text, &file) {
            Ok(_) => panic!("{}: accepted", case.name),
            Err(e) => e,
        };
        insta::assert_snapshot!(case.name, message(&e, &dir));
    }
}

#[test]
fn mesh_error_messages() {
    for case in MESH_CASES {
        let dir = fixture_dir(&format!("snap-{}", case.name));
        std::fs::write(dir.join("broken.obj"), case.obj).unwrap();
        let text = VALID.replacen("path = \"cube.obj\"", "path = \"broken.obj\"", 1);
        let e = match Scene::parse_str(&text, &dir.join("scene.toml")) {
            Ok(_) => panic!("{}: accepted", case.name),
            Err(e) => e,
        };
        insta::assert_snapshot!(case.name, message(&e, &dir));
    }
}

#[test]
fn unreadable_scene_file() {
    let dir = fixture_dir("snap-unreadable");
    let e = Scene::load(&dir.join("absent.toml")).unwrap_err();
    insta::assert_snapshot!("unreadable_scene_file", message(&e, &dir));
}

/// Files that are not scene files: refused by name before they are read (a FIFO would block,
/// `/dev/zero` never ends, a sparse file claims gigabytes).
#[cfg(unix)]
#[test]
fn scene_paths_that_are_not_scene_files() {
    let dir = fixture_dir("snap-not-files");
    let e = Scene::load(std::path::Path::new("/dev/zero")).unwrap_err();
    insta::assert_snapshot!("scene_path_dev_zero", message(&e, &dir));
    let fifo = dir.join("pipe.toml");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let e = Scene::load(&fifo).unwrap_err();
        insta::assert_snapshot!("scene_path_fifo", message(&e, &dir));
    }
    let big = dir.join("big.toml");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(8 << 30).unwrap(); // sparse: no disk space used
    let e = Scene::load(&big).unwrap_err();
    insta::assert_snapshot!("scene_file_too_large", message(&e, &dir));
    std::fs::remove_file(&big).unwrap();
}

/// Mesh files that cannot be meshes: a sparse 8 GB file and a named pipe.
#[cfg(unix)]
#[test]
fn mesh_paths_that_are_not_mesh_files() {
    let dir = fixture_dir("snap-not-meshes");
    let big = dir.join("big.obj");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(8 << 30).unwrap(); // sparse: no disk space used
    let text = VALID.replacen("path = \"cube.obj\"", "path = \"big.obj\"", 1);
    let e = Scene::parse_str(&text, &dir.join("scene.toml")).unwrap_err();
    insta::assert_snapshot!("mesh_file_too_large", message(&e, &dir));
    std::fs::remove_file(&big).unwrap();
    let fifo = dir.join("pipe.obj");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let text = VALID.replacen("path = \"cube.obj\"", "path = \"pipe.obj\"", 1);
        let e = Scene::parse_str(&text, &dir.join("scene.toml")).unwrap_err();
        insta::assert_snapshot!("mesh_path_fifo", message(&e, &dir));
    }
}
