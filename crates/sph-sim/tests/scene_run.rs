//! `cargo xtask run` end to end on a small scene file: frames, statistics, and a blow-up or
//! a malformed scene reported as an error naming the file.

use std::path::PathBuf;

use sph_sim::{run_scene, FrameRecord, SceneRunOptions};

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("scene-run-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const SCENE: &str = r#"
name = "tiny"
[simulation]
precision = "f64"
particle_spacing = 0.025
duration = 0.08
frame_dt = 0.016
[solver]
kind = "KIND"
substeps = 2
iterations = 2
[tank]
min = [0.0, 0.0, 0.0]
max = [0.3, 0.3, 0.2]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.1, 0.15, 0.1]
[output]
every_frames = 2
vtk = true
"#;

#[test]
fn runs_a_scene_and_writes_frames_and_statistics() {
    for (kind, model) in [
        ("pbf", "collision"),
        ("pcisph", "collision"),
        ("pbf", "volume-map"),
        ("pcisph", "volume-map"),
    ] {
        let dir = temp_dir(&format!("{kind}-{model}"));
        let scene = dir.join("tiny.toml");
        let text = format!(
            "{}\n[boundary]\nmodel = \"{model}\"\n",
            SCENE.replace("KIND", kind)
        );
        std::fs::write(&scene, text).unwrap();
        let out = dir.join("out");
        run_scene(
            &scene,
            &SceneRunOptions {
                quick: false,
                out_dir: out.clone(),
                max_frames: None,
                progress: false,
                checkpoint_every: None,
                resume: false,
                render: false,
                volume_map_cache: None,
                overrides: Vec::new(),
                until_rest: None,
                cancel: None,
            },
        )
        .unwrap();
        // 0.08 s of 16 ms frames: 5 frames; VTK at frames 0, 2, 4.
        let stats = std::fs::read_to_string(out.join("stats.csv")).unwrap();
        let lines: Vec<&str> = stats.lines().collect();
        let phases: &[&str] = if kind == "pbf" {
            pbf::PBF_PHASES
        } else {
            pcisph::PCISPH_PHASES
        };
        assert_eq!(lines[0], FrameRecord::csv_header(phases).join(","));
        assert_eq!(lines.len(), 1 + 5, "{stats}");
        let last: Vec<&str> = lines[5].split(',').collect();
        assert_eq!(last[0], "5");
        assert_eq!(last[2], "96", "4 x 6 x 4 particles");
        let max_ratio: f64 = last[3].parse().unwrap();
        assert!(
            max_ratio > 0.9 && max_ratio < 1.2,
            "{kind} {model}: max rho/rho0 {max_ratio}"
        );
        for f in [0, 2, 4] {
            let p = out.join(format!("frame_{f:05}.vtk"));
            let bytes = std::fs::read(&p).unwrap();
            assert!(
                bytes.starts_with(b"# vtk DataFile Version"),
                "{}",
                p.display()
            );
        }
        assert!(!out.join("frame_00001.vtk").exists());
        std::fs::remove_dir_all(&dir).ok();
    }
}

/// The IISPH kinds through the factory: water and granular (with upscaling) run with
/// volume-map walls of the cubic spline; the granular run writes `passive_NNNNN.vtk` beside
/// the frames (from frame 2 on: the points are seeded by the first step), 4 per particle.
#[test]
fn runs_iisph_and_granular_scenes_with_passive_points() {
    for (kind, extra) in [
        ("iisph", ""),
        (
            "granular",
            "friction_angle_deg = 30.0\ndrag_coefficient = 0.5\nupscaling_factor = 4\n",
        ),
    ] {
        let dir = temp_dir(kind);
        let scene = dir.join("tiny.toml");
        let text = SCENE
            .replace("KIND", kind)
            .replace("iterations = 2\n", &format!("max_iterations = 50\n{extra}"));
        std::fs::write(&scene, text).unwrap();
        let out = dir.join("out");
        run_scene(
            &scene,
            &SceneRunOptions {
                quick: false,
                out_dir: out.clone(),
                max_frames: None,
                progress: false,
                checkpoint_every: None,
                resume: false,
                render: false,
                volume_map_cache: None,
                overrides: Vec::new(),
                until_rest: None,
                cancel: None,
            },
        )
        .unwrap();
        let stats = std::fs::read_to_string(out.join("stats.csv")).unwrap();
        let lines: Vec<&str> = stats.lines().collect();
        assert_eq!(
            lines[0],
            FrameRecord::csv_header(iisph_granular::IISPH_PHASES).join(",")
        );
        assert_eq!(lines.len(), 1 + 5, "{stats}");
        for f in [0, 2, 4] {
            assert!(out.join(format!("frame_{f:05}.vtk")).exists());
        }
        let passive = out.join("passive_00002.vtk");
        if kind == "granular" {
            let bytes = std::fs::read(&passive).unwrap();
            assert!(bytes.starts_with(b"# vtk DataFile Version"));
            let text = String::from_utf8_lossy(&bytes);
            assert!(text.contains("POINTS 384 float"), "4 x 96 points");
            assert!(!out.join("passive_00000.vtk").exists());
        } else {
            assert!(!passive.exists());
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[test]
fn malformed_scene_names_file_and_field() {
    let dir = temp_dir("bad");
    let scene = dir.join("bad.toml");
    std::fs::write(
        &scene,
        SCENE
            .replace("KIND", "pbf")
            .replace("particle_spacing = 0.025", "particle_spacing = -0.025"),
    )
    .unwrap();
    let err = run_scene(
        &scene,
        &SceneRunOptions {
            quick: false,
            out_dir: dir.join("out"),
            max_frames: None,
            progress: false,
            checkpoint_every: None,
            resume: false,
            render: false,
            volume_map_cache: None,
            overrides: Vec::new(),
            until_rest: None,
            cancel: None,
        },
    )
    .unwrap_err();
    let msg = format!("{err:#}");
    assert!(msg.contains("bad.toml"), "{msg}");
    assert!(msg.contains("particle_spacing"), "{msg}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn zero_frames_and_a_file_as_output_are_refused() {
    let dir = temp_dir("refuse");
    let scene = dir.join("tiny.toml");
    std::fs::write(&scene, SCENE.replace("KIND", "pbf")).unwrap();
    let opts = |out_dir, max_frames| SceneRunOptions {
        quick: false,
        out_dir,
        max_frames,
        progress: false,
        checkpoint_every: None,
        resume: false,
        render: false,
        volume_map_cache: None,
        overrides: Vec::new(),
        until_rest: None,
        cancel: None,
    };
    let err = run_scene(&scene, &opts(dir.join("out"), Some(0))).unwrap_err();
    assert!(err.to_string().contains("--frames 0"), "{err}");
    let file = dir.join("a-file");
    std::fs::write(&file, "x").unwrap();
    let err = run_scene(&scene, &opts(file, None)).unwrap_err();
    assert!(err.to_string().contains("not a directory"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
