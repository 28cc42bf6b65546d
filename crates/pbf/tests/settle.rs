//! A fluid block at rest in a tank settles: bounded compression, mean density near ρ0, every
//! particle inside the tank, kinetic energy decaying; mass and particle count conserved.

mod common;

use pbf::{Pbf, PbfParams, Real, Sdf};
use sph_core::{BoxSdf, Inverted};

/// 10 × 10 × 10 particles (s = 0.025 m, h = 0.05 m) filling the bottom of a tank of
/// 10 × 20 × 10 spacings, 4 substeps × 10 iterations per 16 ms frame (the paper's
/// compressibility comparison, §8), 63 frames = 1.008 s.
fn settle<R: Real>() {
    let p = PbfParams::<R> {
        solver_iterations: 10,
        ..Default::default()
    };
    let (mut state, solids, tank) = common::block_in_tank(&p, [10, 10, 10], [10.0, 20.0, 10.0]);
    let n = state.len();
    let mass0: f64 = state.masses.iter().map(|m| m.as_f64()).sum();
    let s = p.common.particle_spacing.as_f64();
    let r = p.particle_radius();
    let tank_sdf = Inverted(BoxSdf::new(tank).unwrap());
    let mut solver = Pbf::new(p.clone(), solids).unwrap();
    let mut ke = Vec::new();
    let mut last = None;
    for _ in 0..63 {
        let st = solver.step(&mut state).unwrap();
        ke.push(st.kinetic_energy);
        if std::env::var("PBF_TRACE").is_ok() {
            println!(
                "{} ke {:.3e} max {:.4}",
                R::NAME,
                st.kinetic_energy,
                st.max_density_ratio
            );
        }
        last = Some(st);
    }
    let st = last.unwrap();
    let ke_max = ke.iter().cloned().fold(0.0, f64::max);
    let top = state
        .positions
        .iter()
        .map(|x| x.y.as_f64())
        .fold(f64::MIN, f64::max);
    println!(
        "{}: max ρ/ρ0 {:.4}, mean {:.4}, KE max {:.3e} J, last {:.3e} J, top {:.3} s",
        R::NAME,
        st.max_density_ratio,
        st.mean_density_ratio,
        ke_max,
        ke[ke.len() - 1],
        top / s
    );
    // Particle count and mass conserved, everything finite.
    assert_eq!(state.len(), n);
    let mass1: f64 = state.masses.iter().map(|m| m.as_f64()).sum();
    assert!((mass1 - mass0).abs() <= 1e-6 * mass0);
    assert!(state
        .positions
        .iter()
        .chain(&state.velocities)
        .all(|v| v.iter().all(|c| c.is_finite_value())));
    // Compression: the measured maximum at t = 1 s is 1.027 (f64) and 1.033 (f32), at the
    // bottom corners, where the walls have no boundary particles (the paper's §9 "particle
    // stacking along boundaries"); in a 2 s run 99 % of the particles stay below 1.022. The
    // paper reports compression comparable to PCISPH with this iteration budget (§8,
    // Fig. 4). Bound: 1.05.
    assert!(
        st.max_density_ratio < 1.05,
        "max ρ/ρ0 = {}",
        st.max_density_ratio
    );
    // Mean: slightly below ρ0 (free-surface and wall particles lack neighbours, and s_corr
    // "keeps particle density slightly lower than the rest density", §4). Measured 0.994
    // (both precisions).
    assert!(
        (0.98..1.005).contains(&st.mean_density_ratio),
        "mean ρ/ρ0 = {}",
        st.mean_density_ratio
    );
    // Every particle inside the tank, at least the particle radius from its walls.
    for (i, x) in state.positions.iter().enumerate() {
        let d = tank_sdf.signed_distance(x);
        assert!(
            d.as_f64() >= r.as_f64() * (1.0 - 1e-4),
            "particle {i} at {x:?}: distance to the walls {d}"
        );
    }
    // The free surface stays where it started (10 spacings, no collapse, no boiling).
    assert!((9.5..10.5).contains(&(top / s)), "top at {} s", top / s);
    // Kinetic energy decays: the lattice's free surface and walls lack neighbours, so the
    // first frames pull them in (peak ~4 J); afterwards the mean kinetic energy of each
    // quarter of the run (16 frames) is below that of the previous quarter, the last
    // quarter's mean is below 1 % of the peak, and the residual rms speed at the end is
    // below 10 % of the block's gravity-wave speed √(g H), H = 10 s.
    let quarter = |k: usize| ke[16 * k..(16 * (k + 1)).min(ke.len())].iter().sum::<f64>() / 16.0;
    let q = [quarter(0), quarter(1), quarter(2), quarter(3)];
    println!("quarter means {q:.3?}");
    assert!(q.windows(2).all(|w| w[1] < w[0]), "quarters {q:?}");
    assert!(
        q[3] < 0.01 * ke_max,
        "last quarter {} vs peak {ke_max}",
        q[3]
    );
    let v_rms = (2.0 * ke[ke.len() - 1] / mass0).sqrt();
    let wave = (9.81 * 10.0 * s).sqrt();
    assert!(
        v_rms < 0.1 * wave,
        "v_rms {v_rms} m/s vs √(gH) = {wave} m/s"
    );
}

#[test]
fn block_settles_f64() {
    settle::<f64>();
}

#[test]
fn block_settles_f32() {
    settle::<f32>();
}
