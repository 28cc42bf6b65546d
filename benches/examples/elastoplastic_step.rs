//! The elastic–plastic granular solver's explicit step (Bui et al. 2008,
//! `elastoplastic-granular`) against the IISPH water step, per particle and per simulated
//! second, on the same 59,319 particles of SPlisHSPlasH's dam break at 25 mm spacing, one
//! after the other in one run:
//!
//! ```text
//! RAYON_NUM_THREADS=2 cargo run --release -p benches --example elastoplastic_step -- [FRAMES] [f64] [settled] [E=PA]
//! ```
//!
//! Water: our IISPH with volume-map walls, Δt = 2 ms, from rest (as
//! `examples/iisph_dambreak.rs`), 5 warm-up steps, then `3 FRAMES` timed steps. Granular, by
//! default the same flowing scene: a granular dam break (`benches::dam_break_elastoplastic`:
//! the same block released in the same tank, walls of three rows of no-slip boundary
//! particles, geostatic start) at Young's modulus `E` (default 5.84·10⁵ Pa, the shipped
//! poured heaps' modulus, at which a metre of grains strains elastically by
//! ρ0 g H / E ≈ 0.03, far below tan φ = 0.58); with `settled`, the block held at rest in a
//! box that fits it (`benches::settled_block_elastoplastic`, Bui's 5.84 MPa unless `E=`).
//! Frames of 2 ms (each one substep of `n` explicit steps, `Δt ≤ C h/c_p`, `c_p` the P-wave
//! speed), 1 warm-up frame, then `FRAMES` timed frames (default 10). A frame starts with a
//! reordering (every tenth) and a neighbour search; its explicit steps share the lists
//! while no grain moves more than half the skin. Prints the wall time per explicit step
//! over whole frames (searches included), the phases per step, per particle (grains; the
//! boundary particles are extra work), the ratio to the water step per particle, the ratio
//! per particle and **simulated second** (what users wait for: the water takes one 2 ms
//! step per 2 ms, the grains `n` explicit steps), and a checksum of the grains' end
//! positions (equal checksums mean bitwise equal runs).
use std::time::Instant;

use iisph_granular::{FluidSolver, Iisph, IisphParams, ParticleSet, Real};
use sph_core::{BoxSdf, Inverted};
use sph_kernels::KernelKind;
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapOptions};
use sph_solver::{Solids, StepStats};

/// Seconds per water step (IISPH, volume maps) over `steps` steps after 5 warm-up ones.
fn water<R: Real>(steps: usize) -> (f64, usize) {
    let (p, tank) = benches::dam_break_fluid::<R>();
    let s = R::of_f64(0.025);
    let mut state = ParticleSet::from_positions(
        p,
        R::of_f64(1000.0 * 0.8 * 0.025f64.powi(3)),
        R::of_f64(1000.0),
    );
    let solids: Solids<R> = vec![Box::new(Inverted(BoxSdf::new(tank).expect("tank")))];
    let mut q = IisphParams::<R>::for_spacing(s);
    q.common.dt = R::of_f64(FRAME_S);
    q.common.substeps = 1;
    let b = VolumeMapBoundary::new(
        solids,
        KernelKind::CubicSpline,
        q.common.support_radius,
        tank,
        q.common.particle_radius() * R::of_f64(0.5),
        VolumeMapOptions::default(),
    )
    .expect("volume map");
    let mut solver = Iisph::with_boundary(q, Box::new(b)).expect("params");
    for _ in 0..5 {
        FluidSolver::step(&mut solver, &mut state).expect("water step");
    }
    let t = Instant::now();
    for _ in 0..steps {
        FluidSolver::step(&mut solver, &mut state).expect("water step");
    }
    (t.elapsed().as_secs_f64() / steps as f64, state.len())
}

struct Granular {
    per_step_s: f64,
    grains: usize,
    boundary: usize,
    steps_per_frame: f64,
    phases: Vec<(String, f64)>,
    searches_per_frame: f64,
    checksum: u64,
}

/// The frames of both sides (s): the water's step, the grains' frame.
const FRAME_S: f64 = 0.002;

/// Young's modulus of the shipped poured heaps (Pa), the flowing scene's default.
const HEAPS_YOUNGS_MODULUS_PA: f64 = 5.84e5;

/// The granular scene: the flowing dam break, or the settled block.
#[derive(Clone, Copy)]
enum Scene {
    DamBreak,
    Settled,
}

fn granular<R: Real>(frames: usize, scene: Scene, youngs_modulus_pa: Option<f64>) -> Granular {
    let (mut solver, mut state) = match scene {
        Scene::DamBreak => benches::dam_break_elastoplastic::<R>(
            FRAME_S,
            youngs_modulus_pa.unwrap_or(HEAPS_YOUNGS_MODULUS_PA),
        ),
        Scene::Settled => benches::settled_block_elastoplastic::<R>(
            FRAME_S,
            youngs_modulus_pa.unwrap_or(elastoplastic_granular::DEFAULT_YOUNGS_MODULUS_PA),
        ),
    }
    .expect("granular scene");
    solver.step(&mut state).expect("granular warm-up frame");
    let (_, searches0) = solver.counts();
    let mut sum = StepStats::new(elastoplastic_granular::ELASTOPLASTIC_PHASES);
    let t = Instant::now();
    for _ in 0..frames {
        let stats = solver.step(&mut state).expect("granular frame");
        for (k, (_, secs)) in stats.phases.iter().enumerate() {
            sum.phases.add(k, secs);
        }
        sum.iterations += stats.iterations;
    }
    let wall = t.elapsed().as_secs_f64();
    let steps = sum.iterations as f64;
    let checksum = state
        .positions
        .iter()
        .flat_map(|x| [x.x, x.y, x.z])
        .fold(0xcbf2_9ce4_8422_2325u64, |h, c| {
            (h ^ c.as_f64().to_bits()).wrapping_mul(0x0000_0100_0000_01b3)
        });
    Granular {
        per_step_s: wall / steps,
        grains: state.len(),
        boundary: solver.boundary_particles().len(),
        steps_per_frame: steps / frames as f64,
        phases: sum
            .phases
            .iter()
            .map(|(name, secs)| (name.to_string(), secs / steps))
            .collect(),
        searches_per_frame: (solver.counts().1 - searches0) as f64 / frames as f64,
        checksum,
    }
}

fn run<R: Real>(frames: usize, scene: Scene, youngs_modulus_pa: Option<f64>) {
    let threads = rayon::current_num_threads();
    let (w, n) = water::<R>(3 * frames);
    let g = granular::<R>(frames, scene, youngs_modulus_pa);
    let w_pp = 1e6 * w / n as f64;
    let g_pp = 1e6 * g.per_step_s / g.grains as f64;
    println!(
        "{} rayon threads, {}; water: IISPH on {n} particles, {} steps; granular: {} grains + {} boundary particles, {frames} frames of {:.1} explicit steps, {:.2} neighbour searches per frame",
        threads,
        std::any::type_name::<R>(),
        3 * frames,
        g.grains,
        g.boundary,
        g.steps_per_frame,
        g.searches_per_frame
    );
    println!("water step: {:.2} ms, {w_pp:.3} us per particle", 1e3 * w);
    println!(
        "explicit step: {:.2} ms, {g_pp:.3} us per grain ({:.3} us per grain or boundary particle)",
        1e3 * g.per_step_s,
        1e6 * g.per_step_s / (g.grains + g.boundary) as f64
    );
    let phases: Vec<String> = g
        .phases
        .iter()
        .map(|(name, secs)| format!("{name} {:.2}", 1e3 * secs))
        .collect();
    println!("explicit step phases (ms per step): {}", phases.join(", "));
    println!(
        "explicit step / water step, per particle: {:.3} (target: at most 0.5)",
        g_pp / w_pp
    );
    // Per particle and simulated second: the water advances FRAME_S per step, the grains
    // FRAME_S per `steps_per_frame` explicit steps.
    let w_pps = w_pp / FRAME_S;
    let g_pps = g_pp * g.steps_per_frame / FRAME_S;
    println!(
        "per particle and simulated second: water {:.3} ms, granular {:.3} ms: granular / water {:.2} (target: at most 3)",
        1e-3 * w_pps,
        1e-3 * g_pps,
        g_pps / w_pps
    );
    println!("granular end positions checksum: {:016x}", g.checksum);
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let frames: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(10);
    let scene = if args.iter().any(|a| a == "settled") {
        Scene::Settled
    } else {
        Scene::DamBreak
    };
    let youngs_modulus_pa = args
        .iter()
        .find_map(|a| a.strip_prefix("E="))
        .map(|e| e.parse::<f64>().expect("E=PA: a number of pascals"));
    if args.iter().any(|a| a == "f64") {
        run::<f64>(frames, scene, youngs_modulus_pa);
    } else {
        run::<f32>(frames, scene, youngs_modulus_pa);
    }
}
