//! Side by side with SPlisHSPlasH 2.19's IISPH: our IISPH (water, or granular with
//! `granular`) on its `DamBreakModel` scene at particle radius 0.0125 m (59,319 fluid
//! particles, tank 4 × 3 × 1.5 m, Δt = 0.002 s, one step per frame), from rest, with
//! volume-map walls of the cubic spline (Bender et al. 2019, as SPlisHSPlasH's
//! `boundaryHandlingMethod` 2), iterating to 0.1 % average compression (2–100
//! iterations, relaxed Jacobi ω = 0.5, as SPlisHSPlasH's IISPH):
//!
//! ```text
//! RAYON_NUM_THREADS=1 cargo run --release -p benches --example iisph_dambreak -- [STEPS] [granular] [f64]
//! ```
//!
//! Particle mass `0.8 ρ0 (2r)³` (SPlisHSPlasH's particle volume; its lattice starts
//! under-dense). `granular` adds friction (θ = 30°) and drag (C_D = 1, still air). Prints
//! the mean wall time per step over all steps (as SPlisHSPlasH's "SimStep" average), the
//! mean iteration count, the phase breakdown and the density at the end; the map's build
//! time is printed and not counted.
use std::time::Instant;

use iisph_granular::{FluidSolver, Iisph, IisphParams, ParticleSet, Real, StepStats};
use sph_core::{BoxSdf, Inverted};
use sph_kernels::KernelKind;
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapOptions};
use sph_solver::Solids;

fn run<R: Real>(steps: usize, granular: bool) {
    let (p, tank) = benches::dam_break_fluid::<R>();
    let s = R::of_f64(0.025);
    let mut state = ParticleSet::from_positions(
        p,
        R::of_f64(1000.0 * 0.8 * 0.025f64.powi(3)),
        R::of_f64(1000.0),
    );
    let solids: Solids<R> = vec![Box::new(Inverted(BoxSdf::new(tank).expect("tank")))];
    let mut q = if granular {
        let mut q = IisphParams::<R>::granular(s, R::of_f64(30.0));
        q.granular.as_mut().expect("granular").drag_coefficient = R::one();
        q
    } else {
        IisphParams::<R>::for_spacing(s)
    };
    q.common.dt = R::of_f64(0.002);
    q.common.substeps = 1;
    let t = Instant::now();
    let b = VolumeMapBoundary::new(
        solids,
        KernelKind::CubicSpline,
        q.common.support_radius,
        tank,
        q.common.particle_radius() * R::of_f64(0.5),
        VolumeMapOptions::default(),
    )
    .expect("volume map");
    println!("volume map built in {:.2} s", t.elapsed().as_secs_f64());
    let mut solver = Iisph::with_boundary(q, Box::new(b)).expect("params");
    let mut sum = StepStats::new(solver.phase_names());
    let mut last = StepStats::default();
    // Friction iterations per step -> number of steps (granular).
    let mut histogram = std::collections::BTreeMap::<usize, usize>::new();
    let mut max_ratio = 0.0f64;
    let t = Instant::now();
    for _ in 0..steps {
        last = FluidSolver::step(&mut solver, &mut state).expect("step");
        for (k, (_, secs)) in last.phases.iter().enumerate() {
            sum.phases.add(k, secs);
        }
        sum.iterations += last.iterations;
        sum.unconverged_substeps += last.unconverged_substeps;
        sum.friction_iterations += last.friction_iterations;
        *histogram.entry(last.friction_iterations).or_default() += 1;
        max_ratio = max_ratio.max(last.max_density_ratio);
        sum.unconverged_friction_substeps += last.unconverged_friction_substeps;
    }
    let wall = t.elapsed().as_secs_f64();
    let n = steps as f64;
    println!(
        "{} ({}) on {} particles, {} rayon threads, {steps} steps x 2-100 iterations to 0.1 % average compression",
        FluidSolver::name(&solver),
        std::any::type_name::<R>(),
        state.len(),
        rayon::current_num_threads()
    );
    println!("mean wall time per step: {:.2} ms", 1e3 * wall / n);
    println!(
        "mean iterations per step: {:.2} ({} steps at the maximum without meeting the tolerance)",
        sum.iterations as f64 / n,
        sum.unconverged_substeps
    );
    if granular {
        println!(
            "mean friction iterations per step: {:.2} ({} steps at the cap without meeting the tolerance; last residual {:.2e})",
            sum.friction_iterations as f64 / n,
            sum.unconverged_friction_substeps,
            last.last_friction_residual
        );
        let bins: Vec<String> = histogram.iter().map(|(k, n)| format!("{k}:{n}")).collect();
        println!(
            "friction iterations per step (iterations:steps): {}",
            bins.join(" ")
        );
    }
    let phases: Vec<String> = sum
        .phases
        .iter()
        .map(|(name, secs)| format!("{name} {:.2}", 1e3 * secs / n))
        .collect();
    println!(
        "phases per step (ms): {} (solve {:.3} us per particle-iteration)",
        phases.join(", "),
        1e6 * sum.phase_s("pressure_solve") / (sum.iterations as f64 * state.len() as f64),
    );
    println!(
        "end: max rho/rho0 {:.5}, mean rho/rho0 {:.5}, last iteration's average compression {:.5}, neighbour pairs {}",
        last.max_density_ratio, last.mean_density_ratio, last.last_solve_error, last.neighbour_pairs
    );
    println!("max rho/rho0 over all steps {max_ratio:.5}");
    // Equal checksums mean bitwise equal runs.
    let (checksum, rest) = benches::state_checksums(&state);
    println!("end positions checksum: {checksum:016x}");
    println!("end velocities and densities checksum: {rest:016x}");
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let steps: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(10);
    let granular = args.iter().any(|a| a == "granular");
    if args.iter().any(|a| a == "f64") {
        run::<f64>(steps, granular);
    } else {
        run::<f32>(steps, granular);
    }
}
