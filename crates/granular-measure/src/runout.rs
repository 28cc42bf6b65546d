//! The runout of a collapsed column, planar ([`runout`], [`normalised_runout`]) or
//! axisymmetric ([`radial_runout`]), from its particle positions (conventions and references
//! in the [crate] documentation).
//!
//! # Planar runout
//!
//! A planar column of width `L0` and height `H0` released from the wall at `x = wall_x` (the
//! material spreads towards +x) comes to rest with its front at `x_front`; the runout is
//! `L∞ = x_front − wall_x`, and Lube et al. (2005) compare `(L∞ − L0)/L0` with the aspect
//! ratio `a = H0/L0`. The front is taken as either
//! - [`FrontMethod::ConnectedBulk`] (the default): the particles' `x` sorted from the wall
//!   side, the front is the last `x` before the first gap wider than `max_gap_m` between
//!   consecutive values (so grains thrown ahead of the deposit and separated from it do not
//!   count; the projection onto `x` of a connected deposit has no gap wider than a particle
//!   spacing), or
//! - [`FrontMethod::Quantile`]: the `x` that a fraction `fraction_ahead` of the particles
//!   exceeds (the surge-front convention of the dam-break experiment),
//!
//! plus the particle radius ([`RunoutOptions::particle_radius_m`]), the edge of the last
//! particle.
//!
//! # Radial runout ([`radial_runout`])
//!
//! An axisymmetric column of radius `R0` and height `H0` collapses around its vertical axis;
//! `R∞` is the mean radius of the connected deposit's outline (the largest set of particles
//! connected by steps shorter than a gap, its outermost particle in each of several
//! azimuthal sectors, the particle radius added, averaged over the sectors), compared by
//! Lube, Huppert, Sparks & Hallworth (2004) as `(R∞ − R0)/R0` against `a = H0/R0`. The
//! deposit's slope is [`angle_of_repose`](crate::angle_of_repose) with
//! [`PileShape::Conical`](crate::PileShape::Conical) on the same axis.

use crate::{check_finite, MeasureError};
use sph_core::{Real, Vec3};

const RUNOUT: &str = "runout";

/// How the front of a deposit is located (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrontMethod {
    /// The last particle `x` before the first gap wider than `max_gap_m` (m, > 0) in the
    /// sorted `x` values, from the wall side.
    ConnectedBulk {
        /// Largest gap between consecutive `x` values still counted as connected (m); one to
        /// two particle spacings.
        max_gap_m: f64,
    },
    /// The `x` exceeded by a fraction `fraction_ahead` of the particles (in `[0, 0.5)`; at
    /// least one particle is ahead when it is > 0).
    Quantile {
        /// Fraction of the particles allowed ahead of the front.
        fraction_ahead: f64,
    },
}

/// Options of [`runout`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunoutOptions {
    /// `x` of the wall the column was released from (m); the material spreads towards +x.
    pub wall_x: f64,
    /// How the front is located.
    pub method: FrontMethod,
    /// Added to the front particle's centre: the particle radius (m, ≥ 0).
    pub particle_radius_m: f64,
}

impl RunoutOptions {
    /// The connected-bulk front with gaps up to two particle spacings
    /// (`max_gap_m = 2 · particle_spacing_m`), plus the particle radius.
    pub fn connected(wall_x: f64, particle_spacing_m: f64) -> Self {
        Self {
            wall_x,
            method: FrontMethod::ConnectedBulk {
                max_gap_m: 2.0 * particle_spacing_m,
            },
            particle_radius_m: 0.5 * particle_spacing_m,
        }
    }
}

/// The runout `L∞ = x_front − wall_x` (m) of a deposit spread from the wall at `wall_x`
/// towards +x (method in the module documentation). Errors: no particles, a non-finite
/// position, options out of range.
pub fn runout<R: Real>(
    positions: &[Vec3<R>],
    options: &RunoutOptions,
) -> Result<f64, MeasureError> {
    check_finite(RUNOUT, positions)?;
    let bad = |option, value, reason| MeasureError::InvalidOption {
        what: RUNOUT,
        option,
        value,
        reason,
    };
    if !options.wall_x.is_finite() {
        return Err(bad("wall_x", options.wall_x, "must be finite"));
    }
    if !(options.particle_radius_m.is_finite() && options.particle_radius_m >= 0.0) {
        return Err(bad(
            "particle_radius_m",
            options.particle_radius_m,
            "must be finite and >= 0",
        ));
    }
    let mut xs: Vec<f64> = positions.iter().map(|p| p.x.as_f64()).collect();
    let front = match options.method {
        FrontMethod::ConnectedBulk { max_gap_m } => {
            if !(max_gap_m.is_finite() && max_gap_m > 0.0) {
                return Err(bad("max_gap_m", max_gap_m, "must be finite and > 0"));
            }
            xs.sort_unstable_by(f64::total_cmp);
            let mut front = xs[0];
            for &x in &xs[1..] {
                if x - front > max_gap_m {
                    break;
                }
                front = x;
            }
            front
        }
        FrontMethod::Quantile { fraction_ahead } => {
            if !(fraction_ahead.is_finite() && (0.0..0.5).contains(&fraction_ahead)) {
                return Err(bad("fraction_ahead", fraction_ahead, "must be in [0, 0.5)"));
            }
            let k = if fraction_ahead > 0.0 {
                ((xs.len() as f64 * fraction_ahead) as usize).max(1)
            } else {
                0
            };
            let idx = xs.len() - 1 - k.min(xs.len() - 1);
            *xs.select_nth_unstable_by(idx, f64::total_cmp).1
        }
    };
    Ok(front + options.particle_radius_m - options.wall_x)
}

/// The normalised runout `(L∞ − L0) / L0` of Lube et al. (2005) from the runout `L∞` and the
/// initial column width `L0` (both m). Errors: a non-finite value or `L0 ≤ 0`.
pub fn normalised_runout(runout_m: f64, initial_length_m: f64) -> Result<f64, MeasureError> {
    if !runout_m.is_finite() {
        return Err(MeasureError::InvalidOption {
            what: RUNOUT,
            option: "runout_m",
            value: runout_m,
            reason: "must be finite",
        });
    }
    if !(initial_length_m.is_finite() && initial_length_m > 0.0) {
        return Err(MeasureError::InvalidOption {
            what: RUNOUT,
            option: "initial_length_m",
            value: initial_length_m,
            reason: "must be finite and > 0",
        });
    }
    Ok((runout_m - initial_length_m) / initial_length_m)
}

const RADIAL_RUNOUT: &str = "radial runout";

/// Options of [`radial_runout`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadialRunoutOptions {
    /// The vertical axis `[x, z]` (m) the deposit spread from (the initial column's axis).
    pub axis_xz: [f64; 2],
    /// Number of equal azimuthal sectors (≥ 1) whose fronts are averaged.
    pub sectors: usize,
    /// Two particles closer than this (m, > 0) are connected; one to two particle spacings.
    pub max_gap_m: f64,
    /// Added to each sector's outermost particle centre: the particle radius (m, ≥ 0).
    pub particle_radius_m: f64,
}

impl RadialRunoutOptions {
    /// 16 sectors around `axis_xz`, particles connected up to two spacings apart
    /// (`max_gap_m = 2 · particle_spacing_m`), plus the particle radius.
    pub fn connected(axis_xz: [f64; 2], particle_spacing_m: f64) -> Self {
        Self {
            axis_xz,
            sectors: 16,
            max_gap_m: 2.0 * particle_spacing_m,
            particle_radius_m: 0.5 * particle_spacing_m,
        }
    }

    fn validate(&self) -> Result<(), MeasureError> {
        let bad = |option, value, reason| {
            Err(MeasureError::InvalidOption {
                what: RADIAL_RUNOUT,
                option,
                value,
                reason,
            })
        };
        let [x, z] = self.axis_xz;
        if !(x.is_finite() && z.is_finite()) {
            let v = if x.is_finite() { z } else { x };
            return bad("axis_xz", v, "must be finite");
        }
        if self.sectors == 0 || self.sectors > 1 << 20 {
            return bad("sectors", self.sectors as f64, "must be in [1, 2^20]");
        }
        if !(self.max_gap_m.is_finite() && self.max_gap_m > 0.0) {
            return bad("max_gap_m", self.max_gap_m, "must be finite and > 0");
        }
        if !(self.particle_radius_m.is_finite() && self.particle_radius_m >= 0.0) {
            return bad(
                "particle_radius_m",
                self.particle_radius_m,
                "must be finite and >= 0",
            );
        }
        Ok(())
    }
}

/// The result of [`radial_runout`].
#[derive(Debug, Clone, PartialEq)]
pub struct RadialRunout {
    /// The runout `R∞` (m): the mean over the sectors of [`RadialRunout::sector_fronts_m`].
    pub radius_m: f64,
    /// Each sector's front (m): the largest distance from the axis of a deposit particle in
    /// the sector, plus the particle radius; sector `k` covers the azimuths
    /// `atan2(z − z_axis, x − x_axis) ∈ [−π + 2πk/n, −π + 2π(k+1)/n)`.
    pub sector_fronts_m: Vec<f64>,
    /// Indices (into the input) of the deposit's particles, ascending.
    pub deposit: Vec<usize>,
}

/// The runout of an axisymmetric deposit (a column collapsed around a vertical axis): the
/// mean radius of the **connected deposit**'s outline.
///
/// 1. The deposit is the largest set of particles connected by steps shorter than
///    [`RadialRunoutOptions::max_gap_m`] (the largest connected component of the graph
///    joining particles closer than that; a cell grid finds the pairs in `O(N)`), so grains
///    thrown ahead of it and separated from it do not count.
/// 2. Around the axis, in each of [`RadialRunoutOptions::sectors`] equal azimuthal sectors,
///    the front is the largest horizontal distance from the axis of a deposit particle, plus
///    the particle radius.
/// 3. `R∞` is the mean of the sectors' fronts: the mean radius of the outline (a deposit
///    that is not round, with fingers or lobes, is measured by its mean extent; the sectors'
///    spread shows how round it is).
///
/// Lube et al. (2004, J. Fluid Mech. 508, 175) compare `(R∞ − R0)/R0` with `a = H0/R0`
/// ([`normalised_runout`] with `L0 = R0`). Resolution: a sector's outermost particle centre
/// lies within about one spacing inside the true edge, so `R∞` is within about half a
/// spacing of it with the radius added; a sector must be wide enough at the front (arc
/// `2π R∞ / n` of a few spacings) for its outermost particle to be on the edge.
///
/// Errors ([`MeasureError`]): no particles; a non-finite position (with its index); options
/// out of range; a sector that holds no deposit particle (the deposit does not surround the
/// axis).
pub fn radial_runout<R: Real>(
    positions: &[Vec3<R>],
    options: &RadialRunoutOptions,
) -> Result<RadialRunout, MeasureError> {
    check_finite(RADIAL_RUNOUT, positions)?;
    options.validate()?;
    let pts: Vec<[f64; 3]> = positions
        .iter()
        .map(|p| [p.x.as_f64(), p.y.as_f64(), p.z.as_f64()])
        .collect();
    let deposit = largest_cluster(&pts, options.max_gap_m);
    let n = options.sectors;
    let [cx, cz] = options.axis_xz;
    let mut fronts = vec![f64::NEG_INFINITY; n];
    for &i in &deposit {
        let (dx, dz) = (pts[i][0] - cx, pts[i][2] - cz);
        let phi = dz.atan2(dx);
        let k = ((phi + std::f64::consts::PI) / std::f64::consts::TAU * n as f64) as usize;
        let k = k.min(n - 1);
        fronts[k] = fronts[k].max(dx.hypot(dz));
    }
    if let Some(k) = fronts.iter().position(|f| !f.is_finite()) {
        return Err(MeasureError::Degenerate {
            what: RADIAL_RUNOUT,
            reason: format!(
                "sector {k} of {n} around the axis ({cx}, {cz}) holds no particle of the \
                 connected deposit ({} of {} particles): the deposit does not surround the axis",
                deposit.len(),
                pts.len()
            ),
        });
    }
    for f in &mut fronts {
        *f += options.particle_radius_m;
    }
    Ok(RadialRunout {
        radius_m: fronts.iter().sum::<f64>() / n as f64,
        sector_fronts_m: fronts,
        deposit,
    })
}

/// The indices (ascending) of the largest set of points connected by steps shorter than
/// `gap` (union–find over the pairs a cell grid of cell `gap` proposes); ties go to the set
/// of the lowest index.
fn largest_cluster(pts: &[[f64; 3]], gap: f64) -> Vec<usize> {
    use std::collections::HashMap;
    let cell = |p: &[f64; 3]| p.map(|c| (c / gap).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in pts.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(i);
    }
    let mut parent: Vec<usize> = (0..pts.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let gap2 = gap * gap;
    for (i, p) in pts.iter().enumerate() {
        let c = cell(p);
        for d in 0..27i64 {
            let key = [c[0] + d % 3 - 1, c[1] + (d / 3) % 3 - 1, c[2] + d / 9 - 1];
            let Some(others) = grid.get(&key) else {
                continue;
            };
            for &j in others {
                if j <= i {
                    continue;
                }
                let q = &pts[j];
                let d2 = (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>();
                if d2 < gap2 {
                    let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                    if ri != rj {
                        parent[ri.max(rj)] = ri.min(rj);
                    }
                }
            }
        }
    }
    let mut size = vec![0usize; pts.len()];
    let roots: Vec<usize> = (0..pts.len()).map(|i| root(&mut parent, i)).collect();
    for &r in &roots {
        size[r] += 1;
    }
    let best = (0..pts.len())
        .max_by(|&a, &b| size[a].cmp(&size[b]).then(b.cmp(&a)))
        .unwrap_or(0);
    (0..pts.len()).filter(|&i| roots[i] == best).collect()
}
