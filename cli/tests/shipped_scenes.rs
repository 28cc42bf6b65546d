//! Every shipped scene (`scenes/*.toml`) runs from the command line as a new user would run
//! it: `particles run SCENE --quick` for a few frames, each frame written and read back, the
//! water scenes' frames rendered (`particles render`) and the granular scenes' last frame
//! measured (`particles repose`). The frames' bytes are snapshotted (one thread, so that
//! they are bit-reproducible): a change that moves any shipped scene's state shows here.
//!
//! The frames are written every frame through `--set output.every_frames=1`, which also
//! checks that an override reaches the run and is recorded for `render` and `repose`.

use std::path::{Path, PathBuf};
use std::process::Output;

use sha2::{Digest, Sha256};

mod common;
use common::{run_particles, stderr_of, stdout_of};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("cli sits in the workspace")
        .to_path_buf()
}

/// `particles ARGS` on one thread (so that the frames are bit-reproducible).
fn particles(args: &[&str]) -> Output {
    run_particles(args, &workspace(), &[("RAYON_NUM_THREADS", "1")])
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status.code(),
        stdout_of(o),
        stderr_of(o)
    )
}

/// Frames to run: a few, but enough for a poured scene's first layer (one layer of the
/// quick funnel, 0.1 × 0.06 × 0.02 m at 0.00072 m³/s, is due after 0.167 s: frame 11; the
/// funnel heap's, 0.1 × 0.1 × 0.025 m at 0.004 m³/s, after 0.0625 s: frame 4).
fn frames_of(stem: &str) -> usize {
    if stem.contains("poured") || stem.contains("funnel") {
        12
    } else {
        2
    }
}

/// What one scene's run gave: particle count, fields and the frames' digest.
fn run_scene(scene: &Path, root: &Path, cache: &Path) -> Result<String, String> {
    let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
    let out = root.join(&stem);
    let frames = frames_of(&stem).to_string();
    let o = particles(&[
        "run",
        &scene.to_string_lossy(),
        "--quick",
        "--frames",
        &frames,
        "--out",
        &out.to_string_lossy(),
        "--checkpoint-every",
        "0",
        "--cache",
        &cache.to_string_lossy(),
        "--set",
        "output.every_frames=1",
    ]);
    if !o.status.success() {
        return Err(format!("{stem}: particles run failed\n{}", text(&o)));
    }
    let source = std::fs::read_to_string(out.join("scene_source.txt")).unwrap_or_default();
    if !source.ends_with("quick\nset output.every_frames=1\n") {
        return Err(format!(
            "{stem}: the run did not record its override:\n{source}"
        ));
    }
    let mut hash = Sha256::new();
    let mut last = (0, 0);
    for f in 0..=frames_of(&stem) {
        let path = out.join(format!("frame_{f:05}.vtk"));
        let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        hash.update(&bytes);
        let read = sph_sim::vtk::read_particle_frame(&path)
            .map_err(|e| format!("{stem}: frame {f} does not read back: {e}"))?;
        if read.velocities.as_ref().map(Vec::len) != Some(read.positions.len()) {
            return Err(format!("{stem}: frame {f} has no velocity per particle"));
        }
        last = (f, read.positions.len());
    }
    if last.1 == 0 {
        return Err(format!("{stem}: no particle at frame {}", last.0));
    }
    // The solver's fields, named in the (binary) frame's attribute headers.
    let vtk = std::fs::read(out.join(format!("frame_{:05}.vtk", last.0))).unwrap_or_default();
    let named = |f: &str| {
        let pat = format!(" {f} float");
        vtk.windows(pat.len()).any(|w| w == pat.as_bytes())
    };
    let fields: Vec<&str> = ["stress", "plastic_strain"]
        .into_iter()
        .filter(|f| named(f))
        .collect();
    read_back(&stem, &out)?;
    Ok(format!(
        "scene: {stem} (--quick, {} frames, one thread)\nparticles at frame {}: {}\nsolver fields: {fields:?}\nframes sha256: {:x}\n",
        frames_of(&stem),
        last.0,
        last.1,
        hash.finalize()
    ))
}

/// The frames read back by the command that applies: a granular run's last frame measured
/// (an angle, or "degenerate pile" for a block or column that is not yet a heap: the frame
/// and the recorded scene were read either way), a water run's frames rendered.
fn read_back(stem: &str, out: &Path) -> Result<(), String> {
    let dir = out.to_string_lossy();
    if stem.starts_with("granular") {
        let o = particles(&["repose", &dir]);
        let measured = o.status.success() && stdout_of(&o).contains("angle of repose");
        if !measured && !stderr_of(&o).contains("degenerate pile") {
            return Err(format!("{stem}: particles repose failed\n{}", text(&o)));
        }
    } else {
        let o = particles(&["render", &dir]);
        let png = out.join("render").join("frame_00002.png");
        if !o.status.success() || !png.is_file() {
            return Err(format!("{stem}: particles render failed\n{}", text(&o)));
        }
    }
    Ok(())
}

#[test]
fn every_shipped_scene_runs_from_the_command_line() {
    let root = common::temp_dir("particles-shipped", "scenes");
    let cache = root.join("volume-maps");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(workspace().join("scenes"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 20, "the shipped scenes: {scenes:?}");
    let mut failures = Vec::new();
    for scene in &scenes {
        match run_scene(scene, &root, &cache) {
            Ok(summary) => {
                let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
                insta::assert_snapshot!(stem, summary);
            }
            Err(e) => failures.push(e),
        }
    }
    std::fs::remove_dir_all(&root).ok();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
