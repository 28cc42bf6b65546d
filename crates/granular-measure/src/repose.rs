//! The angle of repose of a settled pile ([`angle_of_repose`]), from its particle positions
//! (conventions in the [crate] documentation).
//!
//! 1. **Free-surface profile.** The particles are binned by their horizontal distance `d`
//!    from the pile's axis — for a conical pile ([`PileShape::Conical`]) the radial distance
//!    from a vertical axis, for a planar (2.5D) heap ([`PileShape::Planar`]) the coordinate
//!    `x` (the heap is uniform along `z`) — in bins of width [`ReposeOptions::bin_width_m`].
//!    In each non-empty bin the highest particle is a point `(d, y)` of the free surface; its
//!    own `d` is kept (not the bin centre), so the bin width only sets how many surface points
//!    there are, not their position. A point more than one bin width below both its
//!    neighbours is dropped: its bin caught only the edge of a column and its highest particle
//!    is buried (bins should be at least about one particle spacing wide).
//! 2. **Flanks.** The apex is the highest particle; its height above the floor is the pile
//!    height `H`. A conical pile has one flank (all `d = r ≥ 0`); a planar heap has up to two,
//!    left and right of the apex, each measured by the distance `|x − x_apex|` (a heap poured
//!    against a wall has one).
//! 3. **Fit.** On each flank, the surface points whose height above the floor lies in
//!    `[f_lo H, f_hi H]` ([`ReposeOptions::fit_band`], default 20 %–80 %: the rounded apex
//!    and the thin toe are left out) are fitted by least squares `y = a + b d`; the flank's
//!    angle is `atan(−b)` (positive for a surface descending away from the apex). A flank with
//!    fewer than [`ReposeOptions::min_fit_points`] points in the band is not fitted; the
//!    pile's angle is the mean of the fitted flanks' angles, and at least one flank must fit.
//! 4. **Steepest slope** (optional, [`ReposeOptions::steepest_run_m`] = `L`): on each
//!    flank, the same least-squares fit over every run of consecutive surface points in the
//!    band whose horizontal extent is at least `L` (the shortest such run from each point);
//!    the flank's steepest slope is the largest of these angles, and the pile's the mean
//!    over the flanks. It shows a concave or domed flank that the band fit averages away. A
//!    run shorter than about 20 spacings follows the steps of the particle lattice (on
//!    straight lattice heaps at 10 mm spacing: 2.8° too steep at `L` = 0.1 m, 1.6° at
//!    0.15 m, 0.8° at 0.2 m; `tests/measure.rs`).
//!
//! Resolution: with surface points whose centres lie between 0 and `δ` below the true
//! surface (δ ≈ one particle spacing for a settled packing, plus `bin_width · tan θ` for the
//! highest particle of a bin sitting anywhere in it), spread evenly over a horizontal run `D`
//! of the flank, the least-squares slope is off by at most `1.5 δ / D` (the bound on
//! `Σ (dᵢ − d̄) eᵢ / Σ (dᵢ − d̄)²` for errors `eᵢ ∈ [0, δ]`), i.e. the angle by at most
//! `atan`-derivative `cos² θ · 1.5 δ / D` radians. [`ReposeMeasurement::resolution_deg`]
//! reports this bound for the measured pile with `δ = spacing + bin_width · tan θ` when the
//! spacing is given in the options.

use crate::{check_finite, MeasureError};
use sph_core::{Real, Vec3};

const REPOSE: &str = "angle of repose";

/// The shape of a pile, which sets the horizontal distance its profile is taken along.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PileShape {
    /// An axisymmetric (conical) pile around a vertical axis through `(x, z) = axis_xz`;
    /// `None` places the axis at the particles' mean `(x, z)`.
    Conical {
        /// The axis position `[x, z]` (m), or `None` for the particles' centroid.
        axis_xz: Option<[f64; 2]>,
    },
    /// A planar (2.5D) heap, uniform along `z`, its profile taken along `x`.
    Planar,
}

/// Options of [`angle_of_repose`] (see the module documentation for the method).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReposeOptions {
    /// Conical pile or planar heap.
    pub shape: PileShape,
    /// Height of the floor the pile rests on (m).
    pub floor_y: f64,
    /// Width of the horizontal bins of the surface profile (m, > 0); one to two particle
    /// spacings.
    pub bin_width_m: f64,
    /// Fractions `[f_lo, f_hi]` of the pile height between which the surface is fitted
    /// (`0 ≤ f_lo < f_hi ≤ 1`; default `[0.2, 0.8]`).
    pub fit_band: [f64; 2],
    /// Fewest surface points in the band for a flank to be fitted (≥ 3; default 4).
    pub min_fit_points: usize,
    /// The particle spacing (m), if known: used only for
    /// [`ReposeMeasurement::resolution_deg`].
    pub particle_spacing_m: Option<f64>,
    /// Horizontal run (m, > 0) of the steepest-slope measure
    /// ([`FlankFit::steepest_deg`]): the largest least-squares slope over any run of
    /// consecutive surface points in the fit band at least this long. `None` (the default)
    /// skips it.
    pub steepest_run_m: Option<f64>,
}

/// The profile and fit options a slope measure shares (`what` names the measure in errors):
/// the bin width finite and > 0, the fit band within `[0, 1]` and increasing, at least three
/// points to a fit.
pub(crate) fn check_fit_options(
    what: &'static str,
    bin_width_m: f64,
    fit_band: [f64; 2],
    min_fit_points: usize,
) -> Result<(), MeasureError> {
    let bad = |option, value, reason| {
        Err(MeasureError::InvalidOption {
            what,
            option,
            value,
            reason,
        })
    };
    if !(bin_width_m.is_finite() && bin_width_m > 0.0) {
        return bad("bin_width_m", bin_width_m, "must be finite and > 0");
    }
    let [lo, hi] = fit_band;
    if !(lo.is_finite() && (0.0..1.0).contains(&lo)) {
        return bad("fit_band[0]", lo, "must be in [0, 1)");
    }
    if !(hi.is_finite() && hi > lo && hi <= 1.0) {
        return bad("fit_band[1]", hi, "must be in (fit_band[0], 1]");
    }
    if min_fit_points < 3 {
        return bad(
            "min_fit_points",
            min_fit_points as f64,
            "must be >= 3 (a line through 2 points has no residual)",
        );
    }
    Ok(())
}

impl ReposeOptions {
    /// A conical pile on the floor `floor_y` with its axis at the particles' centroid, bins
    /// of `bin_width_m`, the 20 %–80 % band and at least 4 points per flank.
    pub fn conical(floor_y: f64, bin_width_m: f64) -> Self {
        Self {
            shape: PileShape::Conical { axis_xz: None },
            floor_y,
            bin_width_m,
            fit_band: [0.2, 0.8],
            min_fit_points: 4,
            particle_spacing_m: None,
            steepest_run_m: None,
        }
    }

    /// A planar heap on the floor `floor_y`, bins of `bin_width_m` along `x`, the 20 %–80 %
    /// band and at least 4 points per flank.
    pub fn planar(floor_y: f64, bin_width_m: f64) -> Self {
        Self {
            shape: PileShape::Planar,
            ..Self::conical(floor_y, bin_width_m)
        }
    }

    /// These options with the particle spacing set (for the resolution estimate).
    pub fn with_spacing(mut self, particle_spacing_m: f64) -> Self {
        self.particle_spacing_m = Some(particle_spacing_m);
        self
    }

    /// These options with the steepest-slope measure over runs of `run_m` (m).
    pub fn with_steepest_run(mut self, run_m: f64) -> Self {
        self.steepest_run_m = Some(run_m);
        self
    }

    fn validate(&self) -> Result<(), MeasureError> {
        let bad = |option, value, reason| {
            Err(MeasureError::InvalidOption {
                what: REPOSE,
                option,
                value,
                reason,
            })
        };
        if !self.floor_y.is_finite() {
            return bad("floor_y", self.floor_y, "must be finite");
        }
        check_fit_options(REPOSE, self.bin_width_m, self.fit_band, self.min_fit_points)?;
        if let PileShape::Conical {
            axis_xz: Some([x, z]),
        } = self.shape
        {
            if !(x.is_finite() && z.is_finite()) {
                return bad(
                    "shape.axis_xz",
                    if x.is_finite() { z } else { x },
                    "must be finite",
                );
            }
        }
        if let Some(s) = self.particle_spacing_m {
            if !(s.is_finite() && s > 0.0) {
                return bad("particle_spacing_m", s, "must be finite and > 0");
            }
        }
        if let Some(l) = self.steepest_run_m {
            if !(l.is_finite() && l > 0.0) {
                return bad("steepest_run_m", l, "must be finite and > 0");
            }
        }
        Ok(())
    }
}

/// A point of the free-surface profile: the highest particle of a bin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Horizontal coordinate (m): radial distance from the axis (conical) or `x` (planar).
    pub d_m: f64,
    /// Height of the particle centre (m).
    pub y_m: f64,
}

/// The least-squares fit of one flank.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlankFit {
    /// Slope angle (degrees), positive for a surface descending away from the apex.
    pub angle_deg: f64,
    /// Surface points in the fit band.
    pub points: usize,
    /// Horizontal run of the fitted points, `max d − min d` (m).
    pub run_m: f64,
    /// Root-mean-square residual of the fit (m).
    pub rms_residual_m: f64,
    /// `-1` for the flank on the −x side of a planar heap's apex, `+1` for the +x side, `0`
    /// for a conical pile.
    pub side: i8,
    /// The steepest slope (degrees) of the flank: the largest least-squares angle over the
    /// runs of consecutive surface points in the fit band whose horizontal extent is at
    /// least [`ReposeOptions::steepest_run_m`]; `None` when that option is `None` or the
    /// band is shorter than the run.
    pub steepest_deg: Option<f64>,
}

/// The result of [`angle_of_repose`].
#[derive(Debug, Clone, PartialEq)]
pub struct ReposeMeasurement {
    /// The pile's angle of repose (degrees): the mean over the fitted flanks.
    pub angle_deg: f64,
    /// Height of the highest particle centre above the floor (m).
    pub pile_height_m: f64,
    /// Horizontal position of the apex (m): its radial distance from the axis (conical) or
    /// its `x` (planar).
    pub apex_d_m: f64,
    /// The fitted flanks (one for a conical pile, one or two for a planar heap).
    pub flanks: Vec<FlankFit>,
    /// The free-surface profile (every bin's highest particle), sorted by `d`.
    pub profile: Vec<SurfacePoint>,
    /// Bound on the angle error from the sampling (degrees), see the module documentation;
    /// `None` without [`ReposeOptions::particle_spacing_m`].
    pub resolution_deg: Option<f64>,
    /// The mean over the flanks of [`FlankFit::steepest_deg`] (degrees); `None` if no flank
    /// has one.
    pub steepest_deg: Option<f64>,
}
/// The free-surface profile of a pile: the highest particle of each bin of width
/// `bin_width_m` along the horizontal coordinate of `shape`, sorted by that coordinate, pits
/// deeper than a bin width below both neighbours removed (see the module documentation). Errors: empty input, a non-finite position, a bad bin width.
pub fn surface_profile<R: Real>(
    positions: &[Vec3<R>],
    shape: PileShape,
    bin_width_m: f64,
) -> Result<Vec<SurfacePoint>, MeasureError> {
    check_finite(REPOSE, positions)?;
    if !(bin_width_m.is_finite() && bin_width_m > 0.0) {
        return Err(MeasureError::InvalidOption {
            what: REPOSE,
            option: "bin_width_m",
            value: bin_width_m,
            reason: "must be finite and > 0",
        });
    }
    let d_of = horizontal_coordinate(positions, shape);
    let d: Vec<f64> = positions.iter().map(d_of).collect();
    let d_min = d.iter().copied().fold(f64::INFINITY, f64::min);
    let d_max = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let bins = ((d_max - d_min) / bin_width_m).floor() as usize + 1;
    if bins > 100_000_000 {
        return Err(MeasureError::InvalidOption {
            what: REPOSE,
            option: "bin_width_m",
            value: bin_width_m,
            reason: "gives more than 1e8 bins over the particles' extent (too small)",
        });
    }
    let mut top: Vec<Option<SurfacePoint>> = vec![None; bins];
    for (p, &d_m) in positions.iter().zip(&d) {
        let b = (((d_m - d_min) / bin_width_m) as usize).min(bins - 1);
        let y_m = p.y.as_f64();
        if top[b].is_none_or(|t| y_m > t.y_m) {
            top[b] = Some(SurfacePoint { d_m, y_m });
        }
    }
    let raw: Vec<SurfacePoint> = top.into_iter().flatten().collect();
    // Pits: a bin that holds only the edge of a column (bins narrower than the spacing, or a
    // bin edge through a column's scatter) has a buried particle as its highest one.
    let keep = |i: usize| {
        if i == 0 || i + 1 == raw.len() {
            return true;
        }
        let floor_of_neighbours = raw[i - 1].y_m.min(raw[i + 1].y_m);
        raw[i].y_m >= floor_of_neighbours - bin_width_m
    };
    Ok((0..raw.len())
        .filter(|&i| keep(i))
        .map(|i| raw[i])
        .collect())
}

/// The horizontal coordinate of `shape` as a function of a position.
fn horizontal_coordinate<R: Real>(
    positions: &[Vec3<R>],
    shape: PileShape,
) -> impl Fn(&Vec3<R>) -> f64 {
    let (conical, cx, cz) = match shape {
        PileShape::Planar => (false, 0.0, 0.0),
        PileShape::Conical {
            axis_xz: Some([x, z]),
        } => (true, x, z),
        PileShape::Conical { axis_xz: None } => {
            let n = positions.len().max(1) as f64;
            let (sx, sz) = positions.iter().fold((0.0, 0.0), |(sx, sz), p| {
                (sx + p.x.as_f64(), sz + p.z.as_f64())
            });
            (true, sx / n, sz / n)
        }
    };
    move |p: &Vec3<R>| {
        if conical {
            (p.x.as_f64() - cx).hypot(p.z.as_f64() - cz)
        } else {
            p.x.as_f64()
        }
    }
}

/// Least-squares line `y = a + b d` through `(d, y)`; returns `(b, rms residual, run)`.
pub(crate) fn fit_line(points: &[(f64, f64)]) -> (f64, f64, f64) {
    let n = points.len() as f64;
    let d_mean = points.iter().map(|p| p.0).sum::<f64>() / n;
    let y_mean = points.iter().map(|p| p.1).sum::<f64>() / n;
    let (mut sdd, mut sdy) = (0.0, 0.0);
    for &(d, y) in points {
        sdd += (d - d_mean) * (d - d_mean);
        sdy += (d - d_mean) * (y - y_mean);
    }
    let b = if sdd > 0.0 { sdy / sdd } else { f64::NAN };
    let rss: f64 = points
        .iter()
        .map(|&(d, y)| (y - y_mean - b * (d - d_mean)).powi(2))
        .sum();
    let d_lo = points.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let d_hi = points.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    (b, (rss / n).sqrt(), d_hi - d_lo)
}

/// The angle of repose of a settled pile from its particle positions (method, resolution and
/// conventions in the module documentation).
///
/// Errors ([`MeasureError`]): no particles; a non-finite position (with its index); options
/// out of range; a degenerate pile — nothing above the floor, or no flank with
/// [`ReposeOptions::min_fit_points`] surface points in the fit band (a flat layer, a pile only
/// a few bins wide).
pub fn angle_of_repose<R: Real>(
    positions: &[Vec3<R>],
    options: &ReposeOptions,
) -> Result<ReposeMeasurement, MeasureError> {
    options.validate()?;
    let profile = surface_profile(positions, options.shape, options.bin_width_m)?;
    let apex = profile
        .iter()
        .copied()
        .max_by(|a, b| a.y_m.total_cmp(&b.y_m))
        .ok_or(MeasureError::Empty { what: REPOSE })?;
    let pile_height_m = apex.y_m - options.floor_y;
    if pile_height_m <= 0.0 {
        return Err(MeasureError::Degenerate {
            what: REPOSE,
            reason: format!(
                "highest particle at y = {} m is not above the floor y = {} m",
                apex.y_m, options.floor_y
            ),
        });
    }
    let [f_lo, f_hi] = options.fit_band;
    let (y_lo, y_hi) = (
        options.floor_y + f_lo * pile_height_m,
        options.floor_y + f_hi * pile_height_m,
    );
    let in_band = |p: &&SurfacePoint| p.y_m >= y_lo && p.y_m <= y_hi;
    let sides: &[i8] = match options.shape {
        PileShape::Conical { .. } => &[0],
        PileShape::Planar => &[-1, 1],
    };
    let mut flanks = Vec::new();
    let mut counts = Vec::new();
    for &side in sides {
        let pts: Vec<(f64, f64)> = profile
            .iter()
            .filter(|p| match side {
                0 => true,
                -1 => p.d_m < apex.d_m,
                _ => p.d_m > apex.d_m,
            })
            .filter(in_band)
            .map(|p| {
                let d = if side == 0 {
                    p.d_m
                } else {
                    (p.d_m - apex.d_m).abs()
                };
                (d, p.y_m)
            })
            .collect();
        counts.push(pts.len());
        if pts.len() < options.min_fit_points {
            continue;
        }
        let (b, rms_residual_m, run_m) = fit_line(&pts);
        if !b.is_finite() {
            continue;
        }
        flanks.push(FlankFit {
            angle_deg: (-b).atan().to_degrees(),
            points: pts.len(),
            run_m,
            rms_residual_m,
            side,
            steepest_deg: options
                .steepest_run_m
                .and_then(|l| steepest_slope_deg(&pts, l, options.min_fit_points)),
        });
    }
    if flanks.is_empty() {
        return Err(MeasureError::Degenerate {
            what: REPOSE,
            reason: format!(
                "no flank has {} surface points between {:.0} % and {:.0} % of the pile height \
                 {:.4} m (points per flank: {:?}; {} profile bins of {} m): a flat layer or a \
                 pile too narrow for the bin width",
                options.min_fit_points,
                100.0 * f_lo,
                100.0 * f_hi,
                pile_height_m,
                counts,
                profile.len(),
                options.bin_width_m
            ),
        });
    }
    let angle_deg = flanks.iter().map(|f| f.angle_deg).sum::<f64>() / flanks.len() as f64;
    let resolution_deg = options.particle_spacing_m.map(|s| {
        let tan = angle_deg.to_radians().tan().abs();
        let delta = s + options.bin_width_m * tan;
        let run = flanks.iter().map(|f| f.run_m).fold(f64::INFINITY, f64::min);
        let cos2 = angle_deg.to_radians().cos().powi(2);
        (cos2 * 1.5 * delta / run).to_degrees()
    });
    let steep: Vec<f64> = flanks.iter().filter_map(|f| f.steepest_deg).collect();
    let steepest_deg = (!steep.is_empty()).then(|| steep.iter().sum::<f64>() / steep.len() as f64);
    Ok(ReposeMeasurement {
        angle_deg,
        pile_height_m,
        apex_d_m: apex.d_m,
        flanks,
        profile,
        resolution_deg,
        steepest_deg,
    })
}

/// The largest least-squares slope angle (degrees, descending away from the apex) over the
/// runs of consecutive points (sorted by `d`) at least `run_m` long with at least
/// `min_points` points; `None` if there is no such run.
fn steepest_slope_deg(points: &[(f64, f64)], run_m: f64, min_points: usize) -> Option<f64> {
    let mut pts = points.to_vec();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best: Option<f64> = None;
    let mut end = 0;
    for start in 0..pts.len() {
        // The shortest window from `start` spanning `run_m`: the steepest is local, and a
        // longer window only averages it with its surroundings.
        end = end.max(start);
        while end < pts.len() && pts[end].0 - pts[start].0 < run_m {
            end += 1;
        }
        if end == pts.len() {
            break;
        }
        let window = &pts[start..=end];
        if window.len() < min_points {
            continue;
        }
        let (b, _, _) = fit_line(window);
        if b.is_finite() {
            let a = (-b).atan().to_degrees();
            best = Some(best.map_or(a, |m: f64| m.max(a)));
        }
    }
    best
}
