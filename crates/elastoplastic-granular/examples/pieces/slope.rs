//! The stress of a planar heap's flanks in the slope's axes, shared by the `drained` and
//! `poured` examples.

use elastoplastic_granular::{Elastoplastic, ParticleSet, Vec3};

/// A test on a grain's position.
pub type GrainTest<'a> = Box<dyn Fn(&Vec3<f64>) -> bool + 'a>;

/// Which grains are the heap's, and how to tell its flanks apart.
pub struct Flanks<'a> {
    /// Whether a grain belongs to the heap.
    pub on_heap: GrainTest<'a>,
    /// Whether a grain of the heap is on its left flank (the flank descending towards `−x`).
    pub left: GrainTest<'a>,
    /// The period along `x` (m).
    pub period_x_m: f64,
    /// The heap's height (m): the layers are taken between 20 % and 80 % of it.
    pub height_m: f64,
}

/// The depth (m) of a grain below the top grain of the heap in its column (columns one
/// spacing `s` wide along `x`).
pub fn floor_depths(
    state: &ParticleSet<f64>,
    flanks: &Flanks<'_>,
    s: f64,
) -> impl Fn(&Vec3<f64>) -> f64 {
    let bins = (flanks.period_x_m / s).ceil() as usize + 1;
    let mut top = vec![f64::NEG_INFINITY; bins];
    for p in &state.positions {
        if (flanks.on_heap)(p) {
            let b = ((p.x / s) as usize).min(bins - 1);
            top[b] = top[b].max(p.y);
        }
    }
    move |p| top[((p.x / s) as usize).min(bins - 1)] - p.y
}

/// The median of the finite values (`NaN` when there is none).
pub fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The flanks' surface layer (0–1 spacing below the top grain of each column) and the layer
/// 2–5 spacings deep, between 20 % and 80 % of the heap's height, at time `t`: the medians
/// of the normal-stress difference along the slope `dN = (σ_ss − σ_nn)/(2 p_in)` (`s`
/// down the slope at `beta_deg`, `n` its outward normal, `p_in = −(σ_ss + σ_nn)/2`;
/// positive: the slope-parallel stress less compressive, an extending layer), `τ/σ_n` on
/// the slope-parallel plane, the yield ratio `√J2/(3 α_φ p)`, the downslope speed (m/s) and
/// the pressure `p` (Pa), as one line.
pub fn layer_state(
    solver: &Elastoplastic<f64>,
    state: &ParticleSet<f64>,
    flanks: &Flanks<'_>,
    s: f64,
    beta_deg: f64,
    alpha_phi: f64,
    t: f64,
) -> String {
    let stress = solver.scheme().stress();
    let depth_of = floor_depths(state, flanks, s);
    let h = flanks.height_m;
    let beta = beta_deg.to_radians();
    let mut out = format!("  layers t {t:.2} beta {beta_deg:.2}:");
    for (lo, hi) in [(-0.1, 1.1), (1.9, 5.1)] {
        let mut rows: Vec<[f64; 5]> = Vec::new();
        for ((p, sg), v) in state.positions.iter().zip(stress).zip(&state.velocities) {
            if !(flanks.on_heap)(p) {
                continue;
            }
            let depth = depth_of(p);
            if !(depth >= lo * s && depth <= hi * s && p.y > 0.2 * h && p.y < 0.8 * h) {
                continue;
            }
            // n the outward normal, d down the slope.
            let sign = if (flanks.left)(p) { -1.0 } else { 1.0 };
            let (sb, cb) = beta.sin_cos();
            let n = nalgebra::Vector3::new(sign * sb, cb, 0.0);
            let d = nalgebra::Vector3::new(sign * cb, -sb, 0.0);
            let snn = n.dot(&(sg * n));
            let sss = d.dot(&(sg * d));
            let tau = d.dot(&(sg * n)).abs();
            let p3 = -sg.trace() / 3.0;
            let dev = sg - nalgebra::Matrix3::identity() * (-p3);
            let j2 = 0.5 * (dev * dev).trace();
            let p_in = -(snn + sss) / 2.0;
            rows.push([
                (sss - snn) / (2.0 * p_in),
                tau / -snn,
                j2.sqrt() / (3.0 * alpha_phi * p3),
                v.dot(&d),
                p3,
            ]);
        }
        let med = |k: usize| median(rows.iter().map(|r| r[k]));
        out += &format!(
            "  [{lo:.0}-{hi:.0}s: n {} dN {:+.3} tau/sn {:.3} yield {:.3} v_down {:.4} p {:.0}]",
            rows.len(),
            med(0),
            med(1),
            med(2),
            med(3),
            med(4)
        );
    }
    out
}
