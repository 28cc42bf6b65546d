//! `particles repose DIR` on a run directory of a still heap and of one whose deep particles
//! creep: the angle, then the rest verdict judged over the run's last second of frames with
//! each quantity's bound and by how much it misses.

mod common;

use std::path::{Path, PathBuf};

use common::{particles_ok, stdout_of, temp_dir};
use sph_core::Vec3;
use sph_sim::vtk::{write_particle_frame, ParticleFrame};

/// A scene of spacing 10 mm and frames of 0.05 s, gravity −9.81 m/s² (the default): the
/// speed bound is 0.05 √(9.81 · 0.01) = 0.01566 m/s.
const SCENE: &str = r#"name = "heap"
[simulation]
precision = "f32"
particle_spacing = 0.01
duration = 1.2
frame_dt = 0.05
[solver]
kind = "pbf"
substeps = 4
iterations = 2
[tank]
min = [0.0, 0.0, 0.0]
max = [0.7, 0.4, 0.03]
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.03]
"#;

/// A planar heap with 30° flanks on a 0.6 m base, three particles across the slab, on a
/// 10 mm lattice; with a flag per particle: at least two spacings below its column's top.
fn heap() -> Vec<(Vec3<f32>, bool)> {
    let (s, tan) = (0.01f64, 30f64.to_radians().tan());
    let mut out = Vec::new();
    for i in 0..=60 {
        let x = i as f64 * s;
        let h = (tan * x.min(0.6 - x) / s).floor() as usize;
        for k in 0..3 {
            for j in 0..=h {
                let p = Vec3::new(x as f32, (j as f64 * s) as f32, (k as f64 * s) as f32);
                out.push((p, j + 2 <= h));
            }
        }
    }
    out
}

/// Frames 0..=24 (t = 0 to 1.2 s) of the heap, its deep particles moving along x at
/// `deep_speed(t)` (m/s), in `dir` with the scene.
fn write_run(dir: &Path, deep_speed: impl Fn(f64) -> f32) -> PathBuf {
    let scene = dir.join("heap.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let heap = heap();
    let positions: Vec<Vec3<f32>> = heap.iter().map(|h| h.0).collect();
    let densities = vec![1000.0f32; heap.len()];
    let ids: Vec<u32> = (0..heap.len() as u32).collect();
    for f in 0..=24usize {
        let t = f as f64 * 0.05;
        let velocities: Vec<Vec3<f32>> = heap
            .iter()
            .map(|&(_, deep)| Vec3::new(if deep { deep_speed(t) } else { 0.0 }, 0.0, 0.0))
            .collect();
        let frame = ParticleFrame {
            time_s: t,
            positions: &positions,
            velocities: &velocities,
            densities: &densities,
            ids: &ids,
            fields: &[],
        };
        write_particle_frame(&dir.join(format!("frame_{f:05}.vtk")), &frame).unwrap();
    }
    scene
}

fn repose(dir: &Path, scene: &Path) -> String {
    let args = [
        "repose",
        dir.to_str().unwrap(),
        "--scene",
        scene.to_str().unwrap(),
    ];
    stdout_of(&particles_ok(args, dir))
}

#[test]
fn a_still_heap_is_at_rest_from_its_first_frame() {
    let dir = temp_dir("particles-repose", "still");
    let scene = write_run(&dir, |_| 0.0);
    let out = repose(&dir, &scene);
    assert!(
        out.contains("rest: at rest at t = 1.200 s (speeds below 0.0157 m/s since t = 0.000 s, angle drift 0.000 deg)"),
        "{out}"
    );
    assert!(
        out.contains("  deep_speed: 0.0000 m/s against 0.0157 m/s: passes"),
        "{out}"
    );
    assert!(
        out.contains("angle_drift: 0.0000 deg against 0.3000 deg: passes"),
        "{out}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_creeping_slab_under_a_still_surface_misses_by_its_speed() {
    // Deep particles at 5 cm/s from t = 0.9 s (the surface still): the deep speed misses
    // by 5 − 1.566 cm/s, and the speeds have not held at all at the last frame.
    let dir = temp_dir("particles-repose", "creep");
    let scene = write_run(&dir, |t| if t >= 0.9 { 0.05 } else { 0.0 });
    let out = repose(&dir, &scene);
    assert!(out.contains("rest: not at rest at t = 1.200 s"), "{out}");
    assert!(
        out.contains("  deep_speed: 0.0500 m/s against 0.0157 m/s: misses by 0.0343 m/s"),
        "{out}"
    );
    assert!(out.contains("speeds held 0.000 s of 0.5 s"), "{out}");
    std::fs::remove_dir_all(&dir).ok();
}
