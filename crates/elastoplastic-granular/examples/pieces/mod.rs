//! The pieces a long example run is split into: `HEAP_BUDGET_S` (stop after this many
//! seconds of wall time), `HEAP_SAVE=FILE` (write the run when it stops) and
//! `HEAP_RESUME=FILE` (continue a saved run; the same arguments must be given). Shared by
//! the `heap_30` and `drained` examples.

#![allow(dead_code)] // each example uses some of the pieces

pub mod args;
pub mod slope;

use granular_measure::{judge_rest, rest_sample, PileShape, RestSample, RestSettings, Vec3};

/// Standard gravity (m/s²) of the examples' set-ups.
pub const GRAVITY_M_S2: f64 = 9.81;

/// The rest criterion's sample of the heap's grains `x`, `v` at `time_s`
/// (`granular_measure::rest` with its default settings, a planar heap; `angle_deg` measured
/// by the caller).
pub fn sample(
    x: &[Vec3<f64>],
    v: &[Vec3<f64>],
    spacing_m: f64,
    time_s: f64,
    angle_deg: Option<f64>,
) -> Result<RestSample, Box<dyn std::error::Error>> {
    let settings = RestSettings::default();
    Ok(rest_sample(
        x,
        v,
        spacing_m,
        PileShape::Planar,
        time_s,
        angle_deg,
        &settings,
    )?)
}

/// Whether the heap is at rest at the last of `samples` by the rest criterion (default
/// settings).
pub fn at_rest(samples: &[RestSample], spacing_m: f64) -> Result<bool, Box<dyn std::error::Error>> {
    let settings = RestSettings::default();
    let bound = settings.speed_bound_m_s(GRAVITY_M_S2, spacing_m)?;
    Ok(judge_rest(samples, bound, &settings)?.at_rest)
}

pub fn elapsed_over_budget(start: &std::time::Instant) -> bool {
    std::env::var("HEAP_BUDGET_S")
        .ok()
        .and_then(|b| b.parse::<f64>().ok())
        .is_some_and(|b| start.elapsed().as_secs_f64() > b)
}

fn push(out: &mut Vec<u8>, values: impl IntoIterator<Item = f64>) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

pub fn save_run(
    path: &str,
    solver: &elastoplastic_granular::Elastoplastic<f64>,
    state: &elastoplastic_granular::ParticleSet<f64>,
    initial: &[elastoplastic_granular::Vec3<f64>],
    ids: &[usize],
    samples: &[RestSample],
) -> Result<(), Box<dyn std::error::Error>> {
    let saved = solver.save_state();
    let mut out = Vec::new();
    push(
        &mut out,
        [
            saved.frames as f64,
            state.len() as f64,
            samples.len() as f64,
        ],
    );
    for x in [&state.positions, &state.velocities, &initial.to_vec()] {
        push(&mut out, x.iter().flat_map(|p| [p.x, p.y, p.z]));
    }
    push(&mut out, state.densities.iter().copied());
    push(&mut out, ids.iter().map(|&k| k as f64));
    for (_, a) in &saved.arrays {
        push(&mut out, a.iter().copied());
    }
    push(
        &mut out,
        samples.iter().flat_map(|s| {
            [
                s.time_s,
                s.percentile_speed_m_s,
                s.deep_max_speed_m_s,
                s.deep_particles as f64,
                s.angle_deg.unwrap_or(f64::NAN),
            ]
        }),
    );
    std::fs::write(path, out)?;
    Ok(())
}

pub fn resume(
    path: &str,
    solver: &mut elastoplastic_granular::Elastoplastic<f64>,
    state: &mut elastoplastic_granular::ParticleSet<f64>,
    initial: &mut [elastoplastic_granular::Vec3<f64>],
    ids: &mut [usize],
    samples: &mut Vec<RestSample>,
) -> Result<usize, Box<dyn std::error::Error>> {
    let bytes = std::fs::read(path)?;
    let mut vals = bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])));
    let mut next = || vals.next().ok_or("the saved run is truncated");
    let frames = next()? as u64;
    let n = next()? as usize;
    let count = next()? as usize;
    if n != state.len() {
        return Err("the saved run has another particle count".into());
    }
    for x in [&mut state.positions[..], &mut state.velocities[..], initial] {
        for p in x.iter_mut() {
            *p = elastoplastic_granular::Vec3::new(next()?, next()?, next()?);
        }
    }
    for r in state.densities.iter_mut() {
        *r = next()?;
    }
    for k in ids.iter_mut() {
        *k = next()? as usize;
    }
    let mut stress = Vec::with_capacity(6 * n);
    for _ in 0..6 * n {
        stress.push(next()?);
    }
    let mut plastic = Vec::with_capacity(n);
    for _ in 0..n {
        plastic.push(next()?);
    }
    for _ in 0..count {
        let (t, p, d, k, a) = (next()?, next()?, next()?, next()?, next()?);
        samples.push(RestSample {
            time_s: t,
            percentile_speed_m_s: p,
            deep_max_speed_m_s: d,
            deep_particles: k as usize,
            angle_deg: (!a.is_nan()).then_some(a),
        });
    }
    let saved = sph_solver::SolverState::new(
        "elastoplastic",
        frames,
        vec![
            ("stress".into(), stress),
            ("plastic_strain".into(), plastic),
        ],
    );
    solver.restore_state(&saved, n)?;
    Ok(frames as usize + 1)
}
