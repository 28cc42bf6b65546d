//! The 30° fixed-base heap (the geometry of `scenes/granular_repose_thesis_30.toml`, quick
//! spacing 10 mm) between free-slip slab walls, run until at rest by the criterion of
//! granular codes or a time cap, with the angle measured as the repose experiment does.
//!
//! ```sh
//! cargo run --release --example heap_30 -p elastoplastic-granular [E_PA] [CAP_S] [PHI_DEG] [CFL] [walls|periodic] [particles|maps] [geo|zero] [WEDGE_DEG|block] [NU] [noslip|free (the base's sides)] [ALPHA_PI] [scene|wide (the base)]
//! ```
//!
//! `HEAP_RESUME=FILE` continues a run saved with `HEAP_SAVE=FILE` (written when the run
//! stops; the same arguments must be given), so that a long run can be split into pieces.
//!
//! Prints every 0.1 s: time, 99th-percentile speed, fastest particle two spacings deep,
//! angle, wall time, the same two speeds without the five outermost columns at each foot,
//! and the bottom grains at each foot (speed, stress, share of the cone); at the end whether the heap is at rest and its angle against the
//! plane-strain prediction `asin(3 α_φ)` (docs/elastoplastic-granular.md).

use std::time::Instant;

use elastoplastic_granular::heap::{
    fixed_base_heap, HeapSetup, SlabSides, BASE_TOP_M, BASE_X_M, WIDE_BASE_X_M,
};
use elastoplastic_granular::stress::plane_strain_alpha;
use elastoplastic_granular::{ElastoplasticParams, WallModel};
use granular_measure::{angle_of_repose, ReposeOptions, RestSample};

mod pieces;
use pieces::{at_rest, elapsed_over_budget, resume, sample, save_run};

const SPACING: f64 = 0.01;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |k: usize, default: f64| -> Result<f64, Box<dyn std::error::Error>> {
        Ok(match std::env::args().nth(k) {
            Some(a) => a.parse()?,
            None => default,
        })
    };
    let youngs = arg(1, 5.84e5)?;
    let cap_s = arg(2, 6.0)?;
    let phi = arg(3, 30.0)?;
    let mut params = ElastoplasticParams::<f64>::for_spacing(SPACING, phi);
    params.youngs_modulus = youngs;
    params.cfl_number = arg(4, params.cfl_number)?;
    params.poisson_ratio = match std::env::args().nth(9) {
        Some(a) => a.parse()?,
        None => params.poisson_ratio,
    };
    params.viscosity_alpha = arg(11, params.viscosity_alpha)?;
    let sides = match std::env::args().nth(5).as_deref() {
        Some("periodic") => SlabSides::Periodic,
        _ => SlabSides::FreeSlipWalls,
    };
    let setup = HeapSetup {
        sides,
        particle_walls: std::env::args().nth(6).as_deref() == Some("particles"),
        geostatic: std::env::args().nth(7).as_deref() == Some("geo"),
        wedge_deg: std::env::args().nth(8).and_then(|a| a.parse().ok()),
        base_sides: match std::env::args().nth(10).as_deref() {
            Some("free") => WallModel::FreeSlip,
            _ => WallModel::NoSlip,
        },
        base_x_m: match std::env::args().nth(12).as_deref() {
            Some("wide") => WIDE_BASE_X_M,
            _ => BASE_X_M,
        },
    };
    let [base_lo, base_hi] = setup.base_x_m;
    println!("{setup:?}");
    let (mut solver, mut state) = fixed_base_heap(params, setup)?;
    let (steps, dt) = solver.params().explicit_steps();
    let predicted = (3.0 * plane_strain_alpha(phi)).asin().to_degrees();
    println!(
        "{} particles, E = {youngs:.3e} Pa, phi = {phi} deg, {steps} explicit steps of {dt:.3e} s per frame; predicted slope {predicted:.2} deg",
        state.len()
    );
    let frame_dt = solver.params().common.dt;
    let options = ReposeOptions::planar(BASE_TOP_M, SPACING).with_spacing(SPACING);
    let mut samples: Vec<RestSample> = Vec::new();
    let mut initial = state.positions.clone();
    // ids[k]: the original index of the particle now at k (the solver reorders them).
    let mut ids: Vec<usize> = (0..state.len()).collect();
    let mut first = 1;
    if let Ok(path) = std::env::var("HEAP_RESUME") {
        first = resume(
            &path,
            &mut solver,
            &mut state,
            &mut initial,
            &mut ids,
            &mut samples,
        )?;
        println!("resumed {path} at frame {first}");
    }
    let start = Instant::now();
    let frames = (cap_s / frame_dt).ceil() as usize;
    let save = |solver: &elastoplastic_granular::Elastoplastic<f64>,
                state: &elastoplastic_granular::ParticleSet<f64>,
                ids: &[usize],
                samples: &[RestSample]|
     -> Result<(), Box<dyn std::error::Error>> {
        if let Ok(path) = std::env::var("HEAP_SAVE") {
            save_run(&path, solver, state, &initial, ids, samples)?;
            println!("saved {path}");
        }
        Ok(())
    };
    for frame in first..=frames {
        if elapsed_over_budget(&start) {
            println!("stopping at frame {frame} (HEAP_BUDGET_S)");
            return save(&solver, &state, &ids, &samples);
        }
        solver.step(&mut state)?;
        if let Some(perm) = solver.last_permutation() {
            ids = perm.iter().map(|&o| ids[o as usize]).collect();
        }
        let t = frame as f64 * frame_dt;
        let (x, v): (Vec<_>, Vec<_>) = state
            .positions
            .iter()
            .zip(&state.velocities)
            .filter(|(p, _)| p.x >= base_lo && p.x <= base_hi && p.y > BASE_TOP_M)
            .map(|(p, u)| (*p, *u))
            .unzip();
        let angle = angle_of_repose(&x, &options).ok().map(|m| m.angle_deg);
        let now = sample(&x, &v, SPACING, t, angle)?;
        let (p99, deep) = (now.percentile_speed_m_s, now.deep_max_speed_m_s);
        samples.push(now);
        let rest = at_rest(&samples, SPACING)?;
        if frame % 6 == 0 || rest {
            // The fastest particle anywhere: where it is, its density ratio and stress.
            let (k, vmax) = state
                .velocities
                .iter()
                .map(|u| u.norm())
                .enumerate()
                .fold((0, 0.0), |a, (k, s)| if s > a.1 { (k, s) } else { a });
            let (i1, _, sq) = elastoplastic_granular::stress::invariants(&solver.stress()[k]);
            let rho0 = solver.params().common.rest_density;
            let (rmin, rmax) = state.densities.iter().fold((f64::MAX, 0.0f64), |a, &r| {
                (a.0.min(r / rho0), a.1.max(r / rho0))
            });
            let p = state.positions[k];
            println!(
                "    fastest {vmax:.3} m/s at ({:.3}, {:.3}, {:.4}) rho/rho0 {:.3} I1 {i1:.0} Pa sqrtJ2 {sq:.0} Pa; rho/rho0 in [{rmin:.3}, {rmax:.3}]",
                p.x, p.y, p.z, state.densities[k] / rho0
            );
            // Displacement from the start of the particles still on the base.
            let mut disp: Vec<f64> = state
                .positions
                .iter()
                .zip(&ids)
                .filter(|(p, _)| p.x >= base_lo && p.x <= base_hi && p.y > BASE_TOP_M)
                .map(|(p, &k)| {
                    // In-plane displacement: z is periodic in one set-up.
                    let d = p - initial[k];
                    (d.x * d.x + d.y * d.y).sqrt()
                })
                .collect();
            disp.sort_by(f64::total_cmp);
            if let (Some(&med), Some(&max)) = (disp.get(disp.len() / 2), disp.last()) {
                println!("    displacement on the base: median {med:.4} m, max {max:.4} m");
            }
            if let Some(q) = x
                .iter()
                .zip(&v)
                .find(|(_, u)| u.norm() == deep)
                .map(|(q, _)| q)
            {
                println!(
                    "    deepest-fastest at ({:.3}, {:.3}, {:.4})",
                    q.x, q.y, q.z
                );
            }
            feet(&solver, &state, &x, base_lo, base_hi);
            println!(
                "t {t:5.2} s  p99 {p99:.4} m/s  deep max {deep:.4} m/s  angle {}  on base {}  wall {:.1} s",
                angle.map_or("-".into(), |a| format!("{a:.2}")),
                x.len(),
                start.elapsed().as_secs_f64()
            );
        }
        if rest && setup.wedge_deg.is_none() {
            println!(
                "AT REST at t = {t:.2} s: angle {} deg (predicted {predicted:.2}), wall time {:.1} s",
                angle.map_or("-".into(), |a| format!("{a:.2}")),
                start.elapsed().as_secs_f64()
            );
            return save(&solver, &state, &ids, &samples);
        }
    }
    let last = samples.last().copied();
    let rest = at_rest(&samples, SPACING)?;
    println!(
        "{} at the cap {cap_s} s: last {last:?} (bound {:.4} m/s), wall time {:.1} s",
        if rest { "AT REST" } else { "NOT AT REST" },
        granular_measure::RestSettings::default().speed_bound_m_s(pieces::GRAVITY_M_S2, SPACING)?,
        start.elapsed().as_secs_f64()
    );
    save(&solver, &state, &ids, &samples)
}

/// The heap without its feet, and the bottom grains of each foot: the rest speeds of the
/// particles more than five spacings inside the heap's ends, then, for the grains of the
/// bottom row within three spacings of each end, their number, fastest speed, mean stress
/// and the share of the cone they use, `√J2 / (−α_φ I1)` (1 on the cone).
fn feet(
    solver: &elastoplastic_granular::Elastoplastic<f64>,
    state: &elastoplastic_granular::ParticleSet<f64>,
    x: &[elastoplastic_granular::Vec3<f64>],
    base_lo: f64,
    base_hi: f64,
) {
    let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.x), a.1.max(p.x))
    });
    let inner = |p: &elastoplastic_granular::Vec3<f64>| {
        p.x > lo + 5.0 * SPACING && p.x < hi - 5.0 * SPACING
    };
    let on_base = |p: &elastoplastic_granular::Vec3<f64>| {
        p.x >= base_lo && p.x <= base_hi && p.y > BASE_TOP_M
    };
    let (xi, vi): (Vec<_>, Vec<_>) = state
        .positions
        .iter()
        .zip(&state.velocities)
        .filter(|(p, _)| on_base(p) && inner(p))
        .map(|(p, u)| (*p, *u))
        .unzip();
    let (p99, deep) = sample(&xi, &vi, SPACING, 0.0, None).map_or((f64::NAN, f64::NAN), |r| {
        (r.percentile_speed_m_s, r.deep_max_speed_m_s)
    });
    println!(
        "    without the feet (x in ({:.3}, {:.3})): p99 {p99:.4} m/s  deep max {deep:.4} m/s",
        lo + 5.0 * SPACING,
        hi - 5.0 * SPACING
    );
    let alpha = solver.params().material().alpha_phi;
    for (name, end, sign) in [("left", lo, 1.0), ("right", hi, -1.0)] {
        let grains: Vec<usize> = (0..state.len())
            .filter(|&k| {
                let p = state.positions[k];
                on_base(&p)
                    && p.y < BASE_TOP_M + 1.5 * SPACING
                    && sign * (p.x - end) < 3.0 * SPACING
            })
            .collect();
        let n = grains.len().max(1) as f64;
        let mut sum = nalgebra::Matrix3::<f64>::zeros();
        let (mut vmax, mut share) = (0.0f64, 0.0);
        for &k in &grains {
            let s = solver.stress()[k];
            sum += s;
            vmax = vmax.max(state.velocities[k].norm());
            let (i1, _, sq) = elastoplastic_granular::stress::invariants(&s);
            share += if i1 < 0.0 { sq / (-alpha * i1) } else { 0.0 };
        }
        let m = sum / n;
        println!(
            "    {name} foot ({end:.3} m): {} bottom grains, fastest {vmax:.4} m/s, mean sxx {:.0} syy {:.0} sxy {:.0} szz {:.0} Pa, mean cone share {:.2}",
            grains.len(),
            m[(0, 0)],
            m[(1, 1)],
            m[(0, 1)],
            m[(2, 2)],
            share / n
        );
    }
}
