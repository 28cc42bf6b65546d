//! A poured heap: grains poured from a funnel that follows the heap's top onto a no-slip
//! floor (`heap::poured_heap`, [`elastoplastic_granular::Pour`]), run until the pour has
//! ended and the heap is at rest by the criterion of granular codes, or a time cap; its
//! angle measured as the repose experiment measures a planar heap (floor `y = 0`).
//!
//! ```sh
//! cargo run --release --example poured -p elastoplastic-granular [key=value …]
//! ```
//!
//! Keys (defaults): `s` spacing (0.02 m), `E` (5.84e5 Pa), `alpha` (α_Π, 0.1), `phi`
//! (30°), `match` the cone's match (`ss` simple shear, the default; `ps` plane strain;
//! `psa` plane strain associated: `ConeMatch`), `cap` (30 s), `L` period (1.6 m), `w` the
//! funnel's width (0.1 m), `area` the cross-section poured (0.16 m²; the volume is it times
//! the slab's depth, three spacings), `q` the rate in m² of cross-section a second (0.012),
//! `layers` (1: every 0.1 s, the flanks' layers' stress in slope axes), `u` the viscosity's
//! fixed velocity scale (m/s; 0, the default: the speed of sound).
//!
//! Prints every 0.1 s: time, grains, 99th-percentile speed and fastest grain two spacings
//! deep, the angle (mean of the flanks) and each flank's, the heap's height, wall time; at
//! the end whether the heap is at rest, its angle against the prediction for a heap formed
//! by flowing (`ConeMatch::predicted_repose_angle_deg`), its surface profile and its
//! packing (the continuity density and each grain's nearest neighbour, quartiles).

use std::time::Instant;

use elastoplastic_granular::heap::{poured_heap, PouredSetup};
use elastoplastic_granular::{ConeMatch, ParticleSet, Vec3};
use granular_measure::{angle_of_repose, ReposeOptions, RestSample};

mod pieces;
use pieces::args::Args;
use pieces::slope::{layer_state, Flanks};
use pieces::{at_rest, sample};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env();
    let (params, s, phi) = args.material(ConeMatch::SimpleShear)?;
    let cone_match = params.cone_match;
    let alpha_phi = cone_match.alpha(phi);
    let cap_s = args.num("cap", 30.0)?;
    let layers = args.num("layers", 0.0)? != 0.0;
    let mut setup = PouredSetup::for_spacing(s);
    setup.period_x_m = args.num("L", setup.period_x_m)?;
    setup.funnel_width_m = args.num("w", setup.funnel_width_m)?;
    setup.volume_m3 = args.num("area", 0.16)? * setup.slab_depth_m;
    setup.rate_m3_s = args.num("q", 0.012)? * setup.slab_depth_m;
    let youngs = params.youngs_modulus;
    let (mut solver, mut state) = poured_heap(params, setup)?;
    let predicted = cone_match.predicted_repose_angle_deg(phi);
    let (_, total) = solver.scheme().poured_layers().unwrap_or((0, 0));
    println!(
        "{setup:?}: {total} layers, s = {s} m, E = {youngs:.3e} Pa, phi = {phi} deg ({cone_match:?}), predicted repose {predicted:.2} deg"
    );
    let frame_dt = solver.params().common.dt;
    let options = ReposeOptions::planar(0.0, s).with_spacing(s);
    let mut samples: Vec<RestSample> = Vec::new();
    let start = Instant::now();
    let frames = (cap_s / frame_dt).ceil() as usize;
    let mut pour_end_s = None;
    let xc = 0.5 * setup.period_x_m;
    for frame in 1..=frames {
        solver.step(&mut state)?;
        let t = frame as f64 * frame_dt;
        if pour_end_s.is_none()
            && solver
                .scheme()
                .poured_layers()
                .is_some_and(|(done, all)| done == all)
        {
            pour_end_s = Some(t);
            println!("the pour ends at t = {t:.2} s with {} grains", state.len());
        }
        let (x, v): (Vec<_>, Vec<_>) = state
            .positions
            .iter()
            .zip(&state.velocities)
            .map(|(p, u)| (*p, *u))
            .unzip();
        if x.is_empty() {
            continue;
        }
        let measured = angle_of_repose(&x, &options).ok();
        let angle = measured.as_ref().map(|m| m.angle_deg);
        let now = sample(&x, &v, s, t, angle)?;
        let (p99, deep) = (now.percentile_speed_m_s, now.deep_max_speed_m_s);
        samples.push(now);
        // At rest only from the pour's end on.
        let poured = pour_end_s.is_some_and(|e| t > e);
        let rest = poured && at_rest(&samples, s)?;
        let flanks = |h| Flanks {
            on_heap: Box::new(|p: &Vec3<f64>| p.y > 0.0),
            left: Box::new(move |p: &Vec3<f64>| p.x < xc),
            period_x_m: setup.period_x_m,
            height_m: h,
        };
        if (layers && frame % 6 == 0) || rest {
            if let Some(m) = &measured {
                let f = flanks(m.pile_height_m);
                println!(
                    "{}",
                    layer_state(&solver, &state, &f, s, m.angle_deg, alpha_phi, t)
                );
            }
        }
        if frame % 6 == 0 || rest {
            let flank_angles = measured.as_ref().map_or(String::new(), |m| {
                m.flanks
                    .iter()
                    .map(|f| format!("{:.2}", f.angle_deg))
                    .collect::<Vec<_>>()
                    .join("/")
            });
            let height = measured.as_ref().map_or(0.0, |m| m.pile_height_m);
            println!(
                "t {t:5.2} s  grains {}  p99 {p99:.4} m/s  deep max {deep:.4} m/s  angle {} (flanks {flank_angles}, height {height:.3} m)  wall {:.1} s",
                state.len(),
                angle.map_or("-".into(), |a| format!("{a:.2}")),
                start.elapsed().as_secs_f64()
            );
        }
        if rest {
            println!(
                "AT REST at t = {t:.2} s: angle {} deg (predicted {predicted:.2}), wall time {:.1} s",
                angle.map_or("-".into(), |a| format!("{a:.2}")),
                start.elapsed().as_secs_f64()
            );
            profile(&state.positions, s);
            packing(
                &state,
                s,
                setup.slab_depth_m,
                solver.params().common.rest_density,
            );
            return Ok(());
        }
    }
    println!(
        "NOT AT REST at the cap {cap_s} s (the pour {}), wall time {:.1} s",
        pour_end_s.map_or("still under way".into(), |e| format!("ended at {e:.2} s")),
        start.elapsed().as_secs_f64()
    );
    profile(&state.positions, s);
    packing(
        &state,
        s,
        setup.slab_depth_m,
        solver.params().common.rest_density,
    );
    Ok(())
}

/// The surface height (mm) in bins of 4 cm along `x`.
fn profile(x: &[Vec3<f64>], s: f64) {
    let bins = 1000;
    let mut top = vec![f64::NEG_INFINITY; bins];
    for p in x {
        let b = ((p.x / 0.04) as usize).min(bins - 1);
        top[b] = top[b].max(p.y + 0.5 * s);
    }
    let shown: Vec<String> = top
        .iter()
        .enumerate()
        .filter(|(_, h)| h.is_finite())
        .map(|(b, h)| format!("{:.2}:{:.0}", (b as f64 + 0.5) * 0.04, 1000.0 * h))
        .collect();
    println!("profile (x m: top mm): {}", shown.join(" "));
}

/// The heap's packing: quartiles of the continuity density over `ρ0`, and of each grain's
/// nearest neighbour's distance in spacings (`z` periodic over `slab` m; all pairs: a
/// printout at the end of a run).
fn packing(state: &ParticleSet<f64>, s: f64, slab: f64, rho0: f64) {
    let quartiles = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let at = |f: f64| v.get(((v.len().max(1) - 1) as f64 * f) as usize).copied();
        let show = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.3}"));
        format!("{}/{}/{}", show(at(0.25)), show(at(0.5)), show(at(0.75)))
    };
    let rho: Vec<f64> = state.densities.iter().map(|r| r / rho0).collect();
    let x = &state.positions;
    let nearest: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, a)| {
            x.iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, b)| {
                    let dz = (a.z - b.z).abs() % slab;
                    let dz = dz.min(slab - dz);
                    ((a.x - b.x).powi(2) + (a.y - b.y).powi(2) + dz * dz).sqrt() / s
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    println!(
        "packing: density/rho0 quartiles {}, nearest neighbour/spacing quartiles {}",
        quartiles(rho),
        quartiles(nearest)
    );
}
