//! The density a scene's fluid starts at, by position against the tank walls, and the
//! largest speed of its first frames.
//!
//! ```text
//! cargo run --release -p sph-sim --example initial_density -- SCENE.toml [--quick]
//!     [--boundary volume-map|collision] [--masses lattice|calibrated] [--frames N]
//! ```
//!
//! Particles are classed by the number of tank faces closer than `0.75 s` (the first
//! lattice layer is `s/2` from a face): 0 = away from the walls (split into "interior",
//! farther than `h` from every face and with a full lattice neighbourhood, and the rest),
//! 1 = wall, 2 = edge, 3 = corner. For each class: count, min, median and max of `ρ/ρ0`
//! (the solver's density kernel, the boundary's share included; `f64` sums). Then the
//! first frames are run and the largest particle speed after each is printed beside the
//! free-fall speed `g t`.

use std::path::PathBuf;

use sph_scene::{BoundaryModel, InitialMasses, Scene};
use sph_sim::observe::OnFrame;
use sph_sim::{density_kernel, run_frames, Flow, FrameRecord, RunPlan, SceneSim};
use sph_solver::initial::density_ratios;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut path = None;
    let (mut quick, mut boundary, mut masses, mut frames) = (false, None, None, 5usize);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--boundary" => boundary = args.next(),
            "--masses" => masses = args.next(),
            "--frames" => frames = args.next().ok_or("--frames N")?.parse()?,
            _ => path = Some(PathBuf::from(a)),
        }
    }
    let path = path.ok_or(
        "usage: initial_density SCENE.toml [--quick] [--boundary M] [--masses M] [--frames N]",
    )?;
    let mut scene = Scene::load(&path)?;
    if quick {
        scene = scene.quick();
    }
    match boundary.as_deref() {
        Some("volume-map") => scene.boundary.model = BoundaryModel::VolumeMap,
        Some("collision") => scene.boundary.model = BoundaryModel::Collision,
        Some(other) => return Err(format!("unknown boundary model {other}").into()),
        None => {}
    }
    match masses.as_deref() {
        Some("lattice") => scene.boundary.initial_masses = InitialMasses::Lattice,
        Some("calibrated") => scene.boundary.initial_masses = InitialMasses::Calibrated,
        Some(other) => return Err(format!("unknown initial masses {other}").into()),
        None => {}
    }
    sph_sim::with_precision!(scene.precision, R => report::<R>(&scene, frames))
}

fn report<R: sph_core::Real>(
    scene: &Scene,
    frames: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut sim = SceneSim::<R>::new(scene)?;
    let s = scene.particle_spacing;
    let common = sim.solver().common().clone();
    let h = common.support_radius.as_f64();
    println!(
        "{}: {} particles, spacing {s} m, h = {h} m, solver {}, boundary {}, kernel {}, masses {:?}",
        scene.source.display(),
        sim.state.len(),
        sim.solver().name(),
        sim.solver().boundary().name(),
        density_kernel(scene),
        scene.boundary.initial_masses
    );
    if let Some(c) = &sim.calibration {
        println!("calibration: {c:?}");
    }
    let ratios = density_ratios(
        density_kernel(scene),
        &common,
        sim.solver().boundary(),
        &sim.state,
    )?;
    let tank = scene.tank.ok_or("the scene has no tank")?;
    let mut classes: [Vec<f64>; 5] = Default::default();
    let names = ["interior", "other (free surface)", "wall", "edge", "corner"];
    let bulk = ratios_bulk(&ratios);
    for (p, &r) in sim.state.positions.iter().zip(&ratios) {
        let mut near = 0;
        let mut min_dist = f64::INFINITY;
        for a in 0..3 {
            for d in [p[a].as_f64() - tank.min[a], tank.max[a] - p[a].as_f64()] {
                if d < 0.75 * s {
                    near += 1;
                }
                min_dist = min_dist.min(d);
            }
        }
        let class = match near {
            0 if min_dist > h && (r - bulk).abs() < 1e-3 => 0,
            0 => 1,
            n => (n + 1).min(4),
        };
        classes[class].push(r);
    }
    println!("class                 count   min      median   max   (rho/rho0)");
    for (name, mut c) in names.iter().zip(classes) {
        if c.is_empty() {
            continue;
        }
        c.sort_by(f64::total_cmp);
        println!(
            "{name:<21} {:>6}   {:.4}   {:.4}   {:.4}",
            c.len(),
            c[0],
            c[c.len() / 2],
            c[c.len() - 1]
        );
    }
    let g = scene.gravity.iter().map(|x| x * x).sum::<f64>().sqrt();
    println!("frame  t (s)    max |v| (m/s)  g t (m/s)  max rho/rho0 (solver)");
    let mut print = OnFrame(|sim: &SceneSim<R>, r: &FrameRecord| {
        println!(
            "{:>5}  {:.4}   {:.4}         {:.4}     {:.4}",
            sim.frame,
            sim.time_s,
            r.max_speed_m_s,
            g * sim.time_s,
            r.max_density_ratio
        );
        Flow::Continue
    });
    let plan = RunPlan::next(&sim, frames);
    run_frames(&mut sim, &plan, &mut [&mut print])?.diverged_as_error()?;
    Ok(())
}

/// The most common ratio (rounded to 1e-4): the lattice's bulk value.
fn ratios_bulk(r: &[f64]) -> f64 {
    let mut v: Vec<i64> = r.iter().map(|x| (x * 1e4).round() as i64).collect();
    v.sort_unstable();
    let (mut best, mut best_n, mut i) = (0, 0, 0);
    while i < v.len() {
        let j = v[i..].iter().take_while(|&&x| x == v[i]).count();
        if j > best_n {
            best_n = j;
            best = v[i];
        }
        i += j;
    }
    best as f64 * 1e-4
}
