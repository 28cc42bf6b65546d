//! A drained heap: a bed of grains on a floor with a slot in its middle, drained into a
//! sump below (`heap::drained_bed`), run until the two slopes left beside the slot are at
//! rest by the criterion of granular codes or a time cap, with their angle measured as
//! the repose experiment measures a planar heap (floor `y = 0`, the grains on the floor).
//!
//! ```sh
//! cargo run --release --example drained -p elastoplastic-granular [key=value …]
//! ```
//!
//! Keys (defaults): `s` spacing (0.02 m), `E` (5.84e5 Pa), `alpha` (α_Π, 0.1), `phi`
//! (30°), `C` (0.2), `cap` (6 s), `L` period (1.2 m), `H` bed height (0.2 m), `w` slot
//! width (0.24 m), `sump` (0.6 m), `geo` (1: geostatic start; 0: unstressed), `k0` the
//! geostatic start's ratio of horizontal to vertical stress (default `ν/(1 − ν)`), `layers`
//! (1: every 0.1 s, the flanks' layers' stress in slope axes, `layer_state`), `u` the
//! viscosity's fixed velocity scale (m/s; 0, the default: the speed of sound), `psi` the
//! dilatancy angle (0°), `door` a trapdoor's speed (m/s; 0, the default: an open slot over
//! the sump; `DrainedSetup::trapdoor_speed_m_s`), `match` the cone's match (`psa` plane strain associated, the
//! default; `ps` plane strain; `ss` simple shear: `ConeMatch`).
//! `HEAP_BUDGET_S`, `HEAP_SAVE`, `HEAP_RESUME` split a long run into pieces (see
//! `examples/pieces`).
//!
//! At rest, also the stress state of the flanks (`flank_stress`). Prints every 0.1 s: time, 99th-percentile speed and fastest particle two spacings deep
//! of the grains on the floor, the angle (mean of the flanks) and each flank's, the grains
//! on the floor, wall time; at the end whether the heap is at rest and its angle against
//! the prediction for a heap formed by flowing, `atan(3 α_φ)`
//! (`ConeMatch::predicted_repose_angle_deg`; docs/elastoplastic-granular.md).

use std::time::Instant;

use elastoplastic_granular::heap::{drained_bed, DrainedSetup};
use elastoplastic_granular::ConeMatch;
use granular_measure::{angle_of_repose, ReposeOptions, RestSample};

mod pieces;
use pieces::args::Args;
use pieces::slope::{floor_depths, layer_state, median, Flanks};
use pieces::{at_rest, elapsed_over_budget, resume, sample, save_run};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env();
    let (mut params, s, phi) = args.material(ConeMatch::PlaneStrainAssociated)?;
    params.cfl_number = args.num("C", params.cfl_number)?;
    params.dilatancy_angle_deg = args.num("psi", 0.0)?;
    let cone_match = params.cone_match;
    let cap_s = args.num("cap", 6.0)?;
    let mut setup = DrainedSetup::for_spacing(s);
    setup.period_x_m = args.num("L", setup.period_x_m)?;
    setup.bed_height_m = args.num("H", setup.bed_height_m)?;
    setup.slot_width_m = args.num("w", setup.slot_width_m)?;
    setup.sump_depth_m = args.num("sump", setup.sump_depth_m)?;
    setup.geostatic = args.num("geo", 1.0)? != 0.0;
    let door = args.num("door", 0.0)?;
    setup.trapdoor_speed_m_s = (door > 0.0).then_some(door);
    println!(
        "{setup:?}, alpha_Pi {}, viscosity speed {:?}, psi {} deg",
        params.viscosity_alpha, params.viscosity_speed_m_s, params.dilatancy_angle_deg
    );
    let youngs = params.youngs_modulus;
    let alpha_phi = cone_match.alpha(phi);
    let k0 = args.num("k0", -1.0)?;
    let layers = args.num("layers", 0.0)? != 0.0;
    let (mut solver, mut state) = drained_bed(params, setup)?;
    if k0 >= 0.0 {
        // The geostatic start with the horizontal stresses K0 times the vertical one.
        let geo = elastoplastic_granular::initial::geostatic(solver.params(), &state.positions)?;
        let set: Vec<_> = geo
            .iter()
            .map(|m| {
                let v = m[(1, 1)];
                nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(k0 * v, v, k0 * v))
            })
            .collect();
        solver.scheme_mut().set_stress(&set)?;
        println!("initial stress: K0 = {k0}");
    }
    let (steps, dt) = solver.params().explicit_steps();
    let predicted = cone_match.predicted_repose_angle_deg(phi);
    println!(
        "{} particles, s = {s} m, E = {youngs:.3e} Pa, phi = {phi} deg ({cone_match:?}), {steps} explicit steps of {dt:.3e} s per frame; predicted repose {predicted:.2} deg (a settled wedge holds to {:.2})",
        state.len(),
        cone_match.max_stable_slope_deg(phi)
    );
    let frame_dt = solver.params().common.dt;
    let options = ReposeOptions::planar(0.0, s).with_spacing(s);
    let mut samples: Vec<RestSample> = Vec::new();
    let mut initial = state.positions.clone();
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
        let t = frame as f64 * frame_dt;
        if let Some(perm) = solver.last_permutation() {
            ids = perm.iter().map(|&o| ids[o as usize]).collect();
        }
        let (x, v): (Vec<_>, Vec<_>) = state
            .positions
            .iter()
            .zip(&state.velocities)
            .filter(|(p, _)| setup.on_floor(p))
            .map(|(p, u)| (*p, *u))
            .unzip();
        let measured = angle_of_repose(&x, &options).ok();
        let angle = measured.as_ref().map(|m| m.angle_deg);
        let now = sample(&x, &v, s, t, angle)?;
        let (p99, deep) = (now.percentile_speed_m_s, now.deep_max_speed_m_s);
        samples.push(now);
        // Not at rest while the trapdoor still moves.
        let rest = at_rest(&samples, s)? && setup.trapdoor_travel_s().is_none_or(|d| t > d);
        if layers && frame % 6 == 0 && !rest {
            if let Some(m) = &measured {
                let line = layer_state(
                    &solver,
                    &state,
                    &flanks(&setup),
                    s,
                    m.angle_deg,
                    alpha_phi,
                    t,
                );
                println!("{line}");
            }
        }
        if frame % 6 == 0 || rest {
            let flanks = measured.as_ref().map_or(String::new(), |m| {
                m.flanks
                    .iter()
                    .map(|f| format!("{:.2}", f.angle_deg))
                    .collect::<Vec<_>>()
                    .join("/")
            });
            let height = measured.as_ref().map_or(0.0, |m| m.pile_height_m);
            println!(
                "t {t:5.2} s  p99 {p99:.4} m/s  deep max {deep:.4} m/s  angle {} (flanks {flanks}, height {height:.3} m)  on floor {}  wall {:.1} s",
                angle.map_or("-".into(), |a| format!("{a:.2}")),
                x.len(),
                start.elapsed().as_secs_f64()
            );
        }
        if rest {
            println!(
                "AT REST at t = {t:.2} s: angle {} deg (predicted {predicted:.2}), wall time {:.1} s",
                angle.map_or("-".into(), |a| format!("{a:.2}")),
                start.elapsed().as_secs_f64()
            );
            profile(&x, s);
            if let Some(m) = &measured {
                flank_stress(&solver, &state, &setup, s, m.angle_deg, alpha_phi);
            }
            return save(&solver, &state, &ids, &samples);
        }
    }
    let last = samples.last().copied();
    let rest = at_rest(&samples, s)?;
    println!(
        "{} at the cap {cap_s} s: last {last:?} (bound {:.4} m/s), wall time {:.1} s",
        if rest { "AT REST" } else { "NOT AT REST" },
        granular_measure::RestSettings::default().speed_bound_m_s(pieces::GRAVITY_M_S2, s)?,
        start.elapsed().as_secs_f64()
    );
    save(&solver, &state, &ids, &samples)
}

/// The surface height (mm) of the grains on the floor in bins of 5 cm along `x`.
fn profile(x: &[elastoplastic_granular::Vec3<f64>], s: f64) {
    let bins = 200;
    let mut top = vec![f64::NEG_INFINITY; bins];
    for p in x {
        let b = ((p.x / 0.05) as usize).min(bins - 1);
        top[b] = top[b].max(p.y + 0.5 * s);
    }
    let shown: Vec<String> = top
        .iter()
        .enumerate()
        .filter(|(_, h)| h.is_finite())
        .map(|(b, h)| format!("{:.3}:{:.0}", (b as f64 + 0.5) * 0.05, 1000.0 * h))
        .collect();
    println!("profile (x m: top mm): {}", shown.join(" "));
}

/// The stress state of each flank at rest: over the grains on the floor two to five
/// spacings below the surface, between 20 % and 80 % of the bed's height, the medians of
/// the friction mobilised on planes parallel to the flank (`τ/σ_n`, to compare with the
/// flank's `tan β`), of the in-plane Mohr circle's `R/p_in` (`sin` of the in-plane
/// mobilised friction; at yield with `s_zz = 0` it is `3 α_φ`), of the Drucker–Prager
/// yield ratio `√J2 / (3 α_φ p)`, of `s_zz/p`, and of the angle of the major (most
/// compressive) principal stress from the horizontal (degrees, measured toward the crest).
/// A flank that stopped in steady simple shear parallel to itself is at yield (ratio 1)
/// with the principal stresses at 45° to its plane and `τ/σ_n = tan β = R/p_in = 3 α_φ`.
fn flank_stress(
    solver: &elastoplastic_granular::Elastoplastic<f64>,
    state: &elastoplastic_granular::ParticleSet<f64>,
    setup: &DrainedSetup,
    s: f64,
    beta_deg: f64,
    alpha_phi: f64,
) {
    let stress = solver.scheme().stress();
    let depth_of = floor_depths(state, &flanks(setup), s);
    let h = setup.bed_height_m;
    let beta = beta_deg.to_radians();
    for (name, left) in [("left", true), ("right", false)] {
        let mut rows: Vec<[f64; 6]> = Vec::new();
        for (p, sg) in state.positions.iter().zip(stress) {
            if !setup.on_floor(p) || (p.x < 0.5 * setup.period_x_m) != left {
                continue;
            }
            let depth = depth_of(p);
            if !(depth >= 1.9 * s && depth <= 5.1 * s && p.y > 0.2 * h && p.y < 0.8 * h) {
                continue;
            }
            let n = if left {
                elastoplastic_granular::Vec3::new(-beta.sin(), beta.cos(), 0.0)
            } else {
                elastoplastic_granular::Vec3::new(beta.sin(), beta.cos(), 0.0)
            };
            let t = sg * n;
            let sn = n.dot(&t);
            let tau = (t - n * sn).norm();
            let (sxx, syy, sxy, szz) = (sg[(0, 0)], sg[(1, 1)], sg[(0, 1)], sg[(2, 2)]);
            let p3 = -(sxx + syy + szz) / 3.0;
            let p_in = -(sxx + syy) / 2.0;
            let r = (((sxx - syy) / 2.0).powi(2) + sxy * sxy).sqrt();
            let dev = sg - nalgebra::Matrix3::identity() * (-p3);
            let j2 = 0.5 * (dev * dev).trace();
            // Major compressive principal direction: the eigenvector of the most negative
            // in-plane principal stress.
            let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
            let major = if sxx + syy - 2.0 * r < 0.0 {
                theta + std::f64::consts::FRAC_PI_2
            } else {
                theta
            };
            let mut ang = major.to_degrees().rem_euclid(180.0);
            if !left {
                ang = 180.0 - ang;
            }
            rows.push([
                tau / -sn,
                r / p_in,
                j2.sqrt() / (3.0 * alpha_phi * p3),
                dev[(2, 2)] / p3,
                ang,
                p3,
            ]);
        }
        let med = |k: usize| median(rows.iter().map(|r| r[k]));
        println!(
            "{name} flank ({} grains, 2-5 spacings deep): tau/sigma_n {:.3} (tan beta {:.3}), R/p_in {:.3} (3 alpha {:.3}), yield ratio {:.3}, s_zz/p {:.3}, major principal stress at {:.1} deg from the horizontal (toward the crest), p {:.0} Pa",
            rows.len(), med(0), beta.tan(), med(1), 3.0 * alpha_phi, med(2), med(3), med(4), med(5)
        );
    }
}

/// The drained bed's two slopes: the grains on the plate, the left one left of the period's
/// middle.
fn flanks(setup: &DrainedSetup) -> Flanks<'_> {
    Flanks {
        on_heap: Box::new(|p| setup.on_floor(p)),
        left: Box::new(|p| p.x < 0.5 * setup.period_x_m),
        period_x_m: setup.period_x_m,
        height_m: setup.bed_height_m,
    }
}
