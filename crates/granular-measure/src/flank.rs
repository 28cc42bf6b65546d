//! The stress of a planar heap's flanks in the slope's axes: how the layers under the
//! surface carry the slope while they flow or after they stop.
//!
//! For each grain of a layer (depth below the top grain of its column, one spacing wide
//! along `x`, between two depths in spacings) between fractions of the heap's height, with
//! `d` the unit vector down its flank's slope at `β` and `n` the flank's outward normal, in
//! the `x`–`y` plane:
//!
//! - `σ_nn = n·σn`, `σ_ss = d·σd`, `τ = |d·σn|` (the stress on the slope-parallel plane);
//! - the normal-stress difference along the slope `dN = (σ_ss − σ_nn)/(2 p_in)`,
//!   `p_in = −(σ_ss + σ_nn)/2` (positive: the slope-parallel stress is less compressive
//!   than the normal one, the layer extends along the slope, as in an active Rankine state;
//!   negative: it is compressed along the slope);
//! - `τ/(−σ_nn)`, the mobilised friction on the slope-parallel plane (`tan β` in a layer
//!   of an infinite slope at rest: Nedderman 1992, *Statics and Kinematics of Granular
//!   Materials*, §5.2);
//! - `√J2/p`, `p = −tr σ/3`, `J2 = s:s/2` (a Drucker–Prager material is at yield where
//!   this ratio reaches `3 α_φ`: divide by `3 α_φ` for the yield ratio);
//! - the speed down the slope `v·d` (m/s) and the pressure `p` (Pa).
//!
//! Each layer reports the medians over its grains (stress tension positive, Pa). The heap's
//! flanks are told apart by the apex: grains left of it are on the flank descending towards
//! `−x`.

use sph_core::Vec3;

use crate::error::MeasureError;

const WHAT: &str = "flank layer stress";

/// Where and how the layers are taken ([`flank_layer_stress`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FlankLayers {
    /// The particle spacing `s` (m): the columns' width and the unit of depth.
    pub spacing_m: f64,
    /// The flanks' slope `β` (degrees, e.g. the measured angle of repose).
    pub slope_deg: f64,
    /// The floor the heap stands on (m).
    pub floor_y: f64,
    /// The apex's `x` (m) that separates the flanks; `None`: the top grain's `x`.
    pub apex_x_m: Option<f64>,
    /// The fractions of the heap's height between which grains are taken.
    pub height_band: (f64, f64),
    /// The layers, each `(from, to)` depths in spacings below the top grain of its column.
    pub layers_spacings: Vec<(f64, f64)>,
}

impl FlankLayers {
    /// The surface layer (0–1 spacing deep) and the layer 2–5 spacings deep, between 20 %
    /// and 80 % of the heap's height, of a heap on the floor `floor_y` sloping at `slope_deg`.
    pub fn new(spacing_m: f64, slope_deg: f64, floor_y: f64) -> Self {
        Self {
            spacing_m,
            slope_deg,
            floor_y,
            apex_x_m: None,
            height_band: (0.2, 0.8),
            layers_spacings: vec![(-0.1, 1.1), (1.9, 5.1)],
        }
    }

    fn check(&self) -> Result<(), MeasureError> {
        let bad = |option, value, reason| {
            Err(MeasureError::InvalidOption {
                what: WHAT,
                option,
                value,
                reason,
            })
        };
        if !(self.spacing_m > 0.0 && self.spacing_m.is_finite()) {
            return bad("spacing_m", self.spacing_m, "a positive, finite length");
        }
        if !(self.slope_deg > 0.0 && self.slope_deg < 90.0) {
            return bad("slope_deg", self.slope_deg, "in (0, 90) degrees");
        }
        let (lo, hi) = self.height_band;
        if !(0.0 <= lo && lo < hi && hi <= 1.0) {
            return bad("height_band", lo, "0 <= from < to <= 1");
        }
        if let Some((a, _)) = self
            .layers_spacings
            .iter()
            .find(|(a, b)| a.partial_cmp(b) != Some(std::cmp::Ordering::Less))
        {
            return bad("layers_spacings", *a, "each layer's from < to");
        }
        Ok(())
    }
}

/// The medians of one layer's grains ([`flank_layer_stress`]; `NaN` for a layer with no
/// grain).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerStress {
    /// The layer's depths (spacings below the top grain of the column).
    pub depth_spacings: (f64, f64),
    /// Grains in the layer.
    pub grains: usize,
    /// `dN = (σ_ss − σ_nn)/(2 p_in)`: positive, the layer extends along the slope.
    pub normal_stress_difference: f64,
    /// `τ/(−σ_nn)` on the slope-parallel plane.
    pub shear_over_normal: f64,
    /// `√J2/p`.
    pub sqrt_j2_over_pressure: f64,
    /// The speed down the slope (m/s).
    pub downslope_speed_m_s: f64,
    /// The pressure `p = −tr σ/3` (Pa).
    pub pressure_pa: f64,
}

/// The stress of the flanks' layers of the heap whose grains are at `positions` (m) with
/// `velocities` (m/s) and `stress` (Pa, tension positive; `xx, yy, zz, xy, yz, zx`), one
/// [`LayerStress`] per layer of `opts` (see the module docs). Errors: empty or mismatched
/// inputs, a non-finite position, options out of range.
pub fn flank_layer_stress(
    positions: &[Vec3<f64>],
    velocities: &[Vec3<f64>],
    stress: &[[f64; 6]],
    opts: &FlankLayers,
) -> Result<Vec<LayerStress>, MeasureError> {
    opts.check()?;
    crate::check_finite(WHAT, positions)?;
    if velocities.len() != positions.len() || stress.len() != positions.len() {
        return Err(MeasureError::LengthMismatch {
            what: WHAT,
            positions: positions.len(),
            velocities: velocities.len().min(stress.len()),
        });
    }
    let s = opts.spacing_m;
    let x0 = positions.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
    let column = |p: &Vec3<f64>| ((p.x - x0) / s) as usize;
    let x1 = positions
        .iter()
        .map(|p| p.x)
        .fold(f64::NEG_INFINITY, f64::max);
    // One column per spacing across the heap: bounded by the grains, not by the input's span.
    let columns = ((x1 - x0) / s) as usize + 1;
    if columns > 16 * positions.len() + 1024 {
        return Err(MeasureError::Degenerate {
            what: WHAT,
            reason: format!(
                "the grains span {} m along x, {columns} columns of {s} m for {} grains: not one heap",
                x1 - x0,
                positions.len()
            ),
        });
    }
    let mut top = vec![f64::NEG_INFINITY; columns];
    for p in positions {
        let c = column(p).min(columns - 1);
        top[c] = top[c].max(p.y);
    }
    let summit = positions.iter().max_by(|a, b| a.y.total_cmp(&b.y));
    let (apex_x, height) = match summit {
        Some(t) => (opts.apex_x_m.unwrap_or(t.x), t.y - opts.floor_y),
        None => return Err(MeasureError::Empty { what: WHAT }),
    };
    let (sb, cb) = opts.slope_deg.to_radians().sin_cos();
    let band = (
        opts.floor_y + opts.height_band.0 * height,
        opts.floor_y + opts.height_band.1 * height,
    );
    let mut out = Vec::with_capacity(opts.layers_spacings.len());
    for &(lo, hi) in &opts.layers_spacings {
        let mut rows: Vec<[f64; 5]> = Vec::new();
        for ((p, v), sg) in positions.iter().zip(velocities).zip(stress) {
            let depth = top[column(p).min(columns - 1)] - p.y;
            if !(depth >= lo * s && depth <= hi * s && p.y > band.0 && p.y < band.1) {
                continue;
            }
            let sign = if p.x < apex_x { -1.0 } else { 1.0 };
            let n = Vec3::new(sign * sb, cb, 0.0);
            let d = Vec3::new(sign * cb, -sb, 0.0);
            rows.push(layer_row(sg, v, &n, &d));
        }
        let med = |k: usize| median(rows.iter().map(|r| r[k]));
        out.push(LayerStress {
            depth_spacings: (lo, hi),
            grains: rows.len(),
            normal_stress_difference: med(0),
            shear_over_normal: med(1),
            sqrt_j2_over_pressure: med(2),
            downslope_speed_m_s: med(3),
            pressure_pa: med(4),
        });
    }
    Ok(out)
}

/// One grain's `[dN, τ/(−σ_nn), √J2/p, v·d, p]` in the slope's axes `n` (outward normal)
/// and `d` (down the slope).
fn layer_row(sg: &[f64; 6], v: &Vec3<f64>, n: &Vec3<f64>, d: &Vec3<f64>) -> [f64; 5] {
    let [xx, yy, zz, xy, yz, zx] = *sg;
    let apply = |u: &Vec3<f64>| {
        Vec3::new(
            xx * u.x + xy * u.y + zx * u.z,
            xy * u.x + yy * u.y + yz * u.z,
            zx * u.x + yz * u.y + zz * u.z,
        )
    };
    let (sn, sd) = (apply(n), apply(d));
    let (snn, sss, tau) = (n.dot(&sn), d.dot(&sd), d.dot(&sn).abs());
    let p = -(xx + yy + zz) / 3.0;
    // J2 = s:s/2 with s = σ + p I (the deviator).
    let (dx, dy, dz) = (xx + p, yy + p, zz + p);
    let j2 = 0.5 * (dx * dx + dy * dy + dz * dz) + xy * xy + yz * yz + zx * zx;
    let p_in = -(snn + sss) / 2.0;
    [
        (sss - snn) / (2.0 * p_in),
        tau / -snn,
        j2.sqrt() / p,
        v.dot(d),
        p,
    ]
}

/// The median of the finite values (the upper one of an even count; `NaN` when there is
/// none).
fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A layer of an infinite slope at rest under gravity carries on the slope-parallel
    /// plane `σ_nn = −ρ g z cos²β`, `τ = ρ g z sin β cos β` (Nedderman 1992 §5.2): the
    /// mobilised friction is `tan β` whatever the stress along the slope.
    #[test]
    fn an_infinite_slope_mobilises_tan_beta() {
        let beta: f64 = 25f64.to_radians();
        let (sb, cb) = beta.sin_cos();
        // Slope axes (right flank): d = (cos β, −sin β), n = (sin β, cos β).
        let (snn, tau, sss) = (-1000.0 * cb * cb, 1000.0 * sb * cb, -400.0);
        // σ = snn n nᵀ + sss d dᵀ + τ (n dᵀ + d nᵀ), in x–y; σ_zz = −500.
        let (n, d) = ((sb, cb), (cb, -sb));
        let c = |a: (f64, f64), b: (f64, f64)| [a.0 * b.0, a.1 * b.1, a.0 * b.1];
        let (nn, dd, nd) = (c(n, n), c(d, d), c(n, d));
        let dn = c(d, n);
        let xx = snn * nn[0] + sss * dd[0] + tau * 2.0 * nd[0];
        let yy = snn * nn[1] + sss * dd[1] + tau * 2.0 * nd[1];
        let xy = snn * nn[2] + sss * dd[2] + tau * (nd[2] + dn[2]);
        let sg = [xx, yy, -500.0, xy, 0.0, 0.0];
        let (nv, dv) = (Vec3::new(sb, cb, 0.0), Vec3::new(cb, -sb, 0.0));
        let r = layer_row(&sg, &Vec3::new(cb, -sb, 0.0), &nv, &dv);
        assert!((r[1] - beta.tan()).abs() < 1e-12, "{}", r[1]);
        let p_in = -(snn + sss) / 2.0;
        assert!((r[0] - (sss - snn) / (2.0 * p_in)).abs() < 1e-12);
        assert!((r[3] - 1.0).abs() < 1e-12, "unit speed down the slope");
        assert!((r[4] - -(xx + yy - 500.0) / 3.0).abs() < 1e-9);
    }

    #[test]
    fn bad_options_and_inputs_are_refused() {
        let x = vec![Vec3::new(0.0, 0.0, 0.0)];
        let v = vec![Vec3::zeros()];
        let sg = vec![[0.0; 6]];
        let mut o = FlankLayers::new(0.01, 30.0, 0.0);
        o.slope_deg = 95.0;
        assert!(flank_layer_stress(&x, &v, &sg, &o).is_err());
        let o = FlankLayers::new(0.01, 30.0, 0.0);
        assert!(flank_layer_stress(&x, &v, &[], &o).is_err());
        assert!(flank_layer_stress(&[], &[], &[], &o).is_err());
    }
}
