//! The angle of repose of a conical heap on a circular base, per azimuthal sector
//! ([`cone_angle_by_sector`]): the fixed-base (funnel) method of ISO 4324:1977 and ASTM
//! C1444-00, in which the heap stands on a disc of radius `R`, grains that reach its rim
//! fall off, and the angle is that of the cone's generatrix, `tan α = H / R` for a perfect
//! cone of height `H`. A heap poured in a simulation is not a perfect cone (a rounded top,
//! a rim that sheds grains, flanks that differ from side to side), so the generatrix is
//! fitted on the flank in each sector, as the planar heap's flanks are
//! ([`crate::angle_of_repose`]), and the spread over azimuth is reported beside the mean
//! (conventions in the [crate] documentation).
//!
//! 1. **Grains on the base.** Only grains at or above the base's top (`y ≥ top_y`) and
//!    within `R + bin_width` of the axis count: grains that fell over the rim are not the
//!    heap's. The heap height `H` is the highest such centre above `top_y`.
//! 2. **Sectors.** The azimuth `φ = atan2(z − z_c, x − x_c)` in `[0°, 360°)` is cut into
//!    `n` equal sectors, sector `k` covering `[k·360°/n, (k+1)·360°/n)`.
//! 3. **Profile per sector.** In each sector, the free-surface profile along the radial
//!    distance `r` ([`crate::surface_profile`] on the sector's grains: the highest grain per
//!    radial bin, buried bins dropped).
//! 4. **Fit per sector.** The profile points from the sector's crest (its highest point)
//!    outward whose height above the base lies in `[f_lo H, f_hi H]`
//!    ([`ConeOptions::fit_band`], default 20 %–80 %: the rounded top and the rim left out)
//!    are fitted by least squares `y = a + b r`. Points nearer the axis than the crest are
//!    not on the flank: a sector's innermost radial bins cover a small area (a 30° sector's
//!    first bin of one spacing holds about a quarter of a lattice column), and their highest
//!    grain may be a buried one, which in the band would pull the fit shallow (one such
//!    point took a 12.5 mm heap's sector to 9.72°, 26.28° without it). The sector's angle is
//!    `atan(−b)`. A sector with fewer than [`ConeOptions::min_fit_points`] points in the band
//!    is listed as not fitted.
//! 5. **Over azimuth.** The mean of the fitted sectors' angles, their sample standard
//!    deviation (`n − 1`), minimum and maximum; at least half the sectors must be fitted.
//!
//! The mean of a perfect cone's sectors is its generatrix angle; a heap whose flanks differ
//! shows it in the spread, which the mean hides (a heap leaning one way stands steeper on
//! one side and shallower on the other with nearly the same mean). The resolution of each
//! sector's fit is that of [`crate::repose`] (module documentation): at most
//! `cos² α · 1.5 δ / D` radians for surface points between 0 and `δ` below the true surface
//! over a radial run `D`.

use crate::repose::{check_fit_options, fit_line, surface_profile, PileShape};
use crate::{check_finite, MeasureError};
use sph_core::{Real, Vec3};

const CONE: &str = "conical heap on a circular base";

/// Most sectors (one a degree).
pub const MAX_SECTORS: usize = 360;

/// The circular base a conical heap stands on: a horizontal disc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConeBase {
    /// The axis' position `[x, z]` (m): the disc's centre.
    pub centre_xz: [f64; 2],
    /// The disc's radius `R` (m, > 0).
    pub radius_m: f64,
    /// The height of the disc's top (m): the heap's floor.
    pub top_y: f64,
}

impl ConeBase {
    /// The base on a horizontal disc of centre `centre` (m, `[x, y, z]`, `y` the disc's
    /// height) and radius `radius_m` (m).
    pub fn on_disc(centre: [f64; 3], radius_m: f64) -> Self {
        ConeBase {
            centre_xz: [centre[0], centre[2]],
            radius_m,
            top_y: centre[1],
        }
    }
}

/// Options of [`cone_angle_by_sector`] (see the module documentation for the method).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConeOptions {
    /// The base the heap stands on.
    pub base: ConeBase,
    /// Number of equal azimuthal sectors (3 to [`MAX_SECTORS`]).
    pub sectors: usize,
    /// Width of the radial bins of each sector's profile (m, > 0); about one spacing.
    pub bin_width_m: f64,
    /// Fractions `[f_lo, f_hi]` of the heap height between which each sector's surface is
    /// fitted (`0 ≤ f_lo < f_hi ≤ 1`; default `[0.2, 0.8]`).
    pub fit_band: [f64; 2],
    /// Fewest profile points in the band for a sector to be fitted (≥ 3; default 3).
    pub min_fit_points: usize,
}

impl ConeOptions {
    /// `sectors` sectors over `base`, radial bins of `bin_width_m`, the 20 %–80 % band and
    /// at least 3 points per sector.
    pub fn new(base: ConeBase, sectors: usize, bin_width_m: f64) -> Self {
        Self {
            base,
            sectors,
            bin_width_m,
            fit_band: [0.2, 0.8],
            min_fit_points: 3,
        }
    }

    fn validate(&self) -> Result<(), MeasureError> {
        let bad = |option, value, reason| {
            Err(MeasureError::InvalidOption {
                what: CONE,
                option,
                value,
                reason,
            })
        };
        let ConeBase {
            centre_xz: [x, z],
            radius_m,
            top_y,
        } = self.base;
        if !(x.is_finite() && z.is_finite()) {
            let value = if x.is_finite() { z } else { x };
            return bad("base.centre_xz", value, "must be finite");
        }
        if !(radius_m.is_finite() && radius_m > 0.0) {
            return bad("base.radius_m", radius_m, "must be finite and > 0");
        }
        if !top_y.is_finite() {
            return bad("base.top_y", top_y, "must be finite");
        }
        if !(3..=MAX_SECTORS).contains(&self.sectors) {
            return bad(
                "sectors",
                self.sectors as f64,
                "must be in [3, 360] (fewer cannot show a spread over azimuth)",
            );
        }
        check_fit_options(CONE, self.bin_width_m, self.fit_band, self.min_fit_points)
    }
}

/// The fit of one azimuthal sector.
#[derive(Debug, Clone, PartialEq)]
pub struct SectorFit {
    /// The sector's azimuths `[from, to)` (degrees, from +x towards +z).
    pub azimuth_deg: [f64; 2],
    /// The generatrix angle (degrees), positive for a surface descending away from the
    /// axis; `None` when the sector has fewer than [`ConeOptions::min_fit_points`] profile
    /// points in the band.
    pub angle_deg: Option<f64>,
    /// Profile points in the band.
    pub points: usize,
    /// Radial run of the fitted points (m).
    pub run_m: f64,
    /// Root-mean-square residual of the fit (m).
    pub rms_residual_m: f64,
    /// The sector's free-surface profile (`d_m` the radial distance), sorted by radius.
    pub profile: Vec<crate::SurfacePoint>,
}

/// The result of [`cone_angle_by_sector`].
#[derive(Debug, Clone, PartialEq)]
pub struct ConeMeasurement {
    /// The mean over the fitted sectors of their angles (degrees).
    pub mean_deg: f64,
    /// The sample standard deviation of the fitted sectors' angles (degrees, `n − 1`).
    pub std_deg: f64,
    /// The smallest fitted sector angle (degrees).
    pub min_deg: f64,
    /// The largest fitted sector angle (degrees).
    pub max_deg: f64,
    /// Sectors fitted.
    pub fitted: usize,
    /// Grains on the base (at or above its top, within `R` plus a bin of the axis).
    pub grains_on_base: usize,
    /// Height of the highest grain centre above the base's top (m).
    pub height_m: f64,
    /// Every sector, fitted or not, in azimuthal order.
    pub sectors: Vec<SectorFit>,
}

/// The angle of a conical heap's generatrix per azimuthal sector, its mean and spread over
/// azimuth (method in the module documentation).
///
/// Errors ([`MeasureError`]): no particles; a non-finite position (with its index); options
/// out of range; a degenerate heap — no grain on the base, none above its top, or fewer
/// than half the sectors fitted (a flat layer, a heap too small for the sectors and bins).
pub fn cone_angle_by_sector<R: Real>(
    positions: &[Vec3<R>],
    options: &ConeOptions,
) -> Result<ConeMeasurement, MeasureError> {
    options.validate()?;
    check_finite(CONE, positions)?;
    let ConeBase {
        centre_xz: [cx, cz],
        radius_m,
        top_y,
    } = options.base;
    let reach = radius_m + options.bin_width_m;
    let on_base: Vec<Vec3<f64>> = positions
        .iter()
        .map(|p| p.map(|c| c.as_f64()))
        .filter(|p| p.y >= top_y && (p.x - cx).hypot(p.z - cz) <= reach)
        .collect();
    let height_m = on_base
        .iter()
        .map(|p| p.y - top_y)
        .fold(f64::NEG_INFINITY, f64::max);
    if on_base.is_empty() || height_m <= 0.0 {
        return Err(MeasureError::Degenerate {
            what: CONE,
            reason: format!(
                "{} grains on the base (radius {radius_m} m at ({cx}, {cz}), top y = {top_y} m), none above its top",
                on_base.len()
            ),
        });
    }
    let n = options.sectors;
    let width = 360.0 / n as f64;
    let mut by_sector: Vec<Vec<Vec3<f64>>> = vec![Vec::new(); n];
    for p in &on_base {
        let phi = (p.z - cz).atan2(p.x - cx).to_degrees().rem_euclid(360.0);
        by_sector[((phi / width) as usize).min(n - 1)].push(*p);
    }
    let band = [
        top_y + options.fit_band[0] * height_m,
        top_y + options.fit_band[1] * height_m,
    ];
    let sectors = by_sector
        .iter()
        .enumerate()
        .map(|(k, grains)| {
            let azimuth_deg = [k as f64 * width, (k + 1) as f64 * width];
            fit_sector(grains, azimuth_deg, band, options)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let angles: Vec<f64> = sectors.iter().filter_map(|s| s.angle_deg).collect();
    if 2 * angles.len() < n {
        return Err(MeasureError::Degenerate {
            what: CONE,
            reason: format!(
                "{} of {n} sectors fitted (each needs {} profile points between {:.0} % and {:.0} % of the heap height {height_m:.4} m; points per sector: {:?}): a flat layer or a heap too small for {n} sectors and bins of {} m",
                angles.len(),
                options.min_fit_points,
                100.0 * options.fit_band[0],
                100.0 * options.fit_band[1],
                sectors.iter().map(|s| s.points).collect::<Vec<_>>(),
                options.bin_width_m
            ),
        });
    }
    let (mean_deg, std_deg) = mean_and_std(&angles);
    Ok(ConeMeasurement {
        mean_deg,
        std_deg,
        min_deg: angles.iter().copied().fold(f64::INFINITY, f64::min),
        max_deg: angles.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        fitted: angles.len(),
        grains_on_base: on_base.len(),
        height_m,
        sectors,
    })
}

/// One sector's profile and fit between the heights `band` (m).
fn fit_sector(
    grains: &[Vec3<f64>],
    azimuth_deg: [f64; 2],
    band: [f64; 2],
    options: &ConeOptions,
) -> Result<SectorFit, MeasureError> {
    let mut fit = SectorFit {
        azimuth_deg,
        angle_deg: None,
        points: 0,
        run_m: 0.0,
        rms_residual_m: 0.0,
        profile: Vec::new(),
    };
    if grains.is_empty() {
        return Ok(fit);
    }
    let shape = PileShape::Conical {
        axis_xz: Some(options.base.centre_xz),
    };
    fit.profile = surface_profile(grains, shape, options.bin_width_m)?;
    // The generatrix runs from the sector's crest outward: a profile point nearer the axis
    // than the crest is not on the flank (the innermost bins of a sector are small, and
    // their highest grain may be a buried one).
    let crest = fit.profile.iter().enumerate().fold(0, |best, (i, p)| {
        if p.y_m > fit.profile[best].y_m {
            i
        } else {
            best
        }
    });
    let pts: Vec<(f64, f64)> = fit.profile[crest..]
        .iter()
        .filter(|p| p.y_m >= band[0] && p.y_m <= band[1])
        .map(|p| (p.d_m, p.y_m))
        .collect();
    fit.points = pts.len();
    if pts.len() >= options.min_fit_points {
        let (b, rms, run) = fit_line(&pts);
        if b.is_finite() {
            fit.angle_deg = Some((-b).atan().to_degrees());
            fit.rms_residual_m = rms;
            fit.run_m = run;
        }
    }
    Ok(fit)
}

/// The mean and the sample standard deviation (`n − 1`; 0 for one value) of `x`.
fn mean_and_std(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = if x.len() > 1 {
        x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (mean, var.sqrt())
}
