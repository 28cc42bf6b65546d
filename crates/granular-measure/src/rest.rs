//! Whether a granular heap is at rest, judged on robust statistics of its particles over
//! time rather than on its single fastest particle.
//!
//! **Sample** ([`rest_sample`], one per frame): from the positions and velocities of the
//! heap's particles,
//!
//! - `v99`, the 99th-percentile speed (nearest rank: the `⌈0.99 N⌉`-th smallest of the `N`
//!   speeds). The largest speed is an extreme of `N` values: one grain rattling on the free
//!   surface, or caught at a wall, keeps it high while the heap stands still, and it grows
//!   with `N`; a high percentile ignores the last percent and is what the bulk does.
//! - `v_deep`, the largest speed of the particles at least two spacings below the local
//!   surface: the particles are put in columns one spacing `s` wide (along `x` for a
//!   planar heap, square `s × s` cells in `(x, z)` for a conical pile), the surface of a
//!   column is its highest particle, and a particle is deep when it lies at least `2 s`
//!   below it. This catches what the percentile can hide: a slab creeping under a still
//!   surface. Columns one spacing wide hold one particle per layer of a settled packing: a
//!   wider column on a flank of slope `θ` would take its surface from its high side and
//!   count surface particles of its low side as deep once `w tan θ ≥ 2 s` (`w` the width,
//!   at θ = 40° from `w = 2.4 s`); a narrower one misses the surface particle of some
//!   columns and counts the layer below as the surface (one spacing off, inside the margin
//!   of two).
//! - the heap's angle of repose (degrees), as [`crate::angle_of_repose`] measures it (given
//!   by the caller, who chooses its options; `None` when it cannot be measured).
//!
//! **Judge** ([`judge_rest`], over the samples of a run in time order): the heap is at rest
//! at the last sample when
//!
//! 1. `v99` and `v_deep` have both stayed below `c √(g s)` (`c` = 0.05) for the last
//!    `T_hold` = 0.5 s, and
//! 2. the angle has been measured at every sample of the last `T_angle` = 1 s (samples
//!    covering the whole second) and its largest minus smallest value there is below
//!    `Δθ` = 0.3°.
//!
//! `√(g s)` is the velocity scale of a grain of size `s` under gravity (the one that makes
//! the inertial number and the Froude number of granular flows dimensionless, e.g. GDR
//! MiDi, "On dense granular flows", *Eur. Phys. J. E* 14, 341–365, 2004,
//! doi:10.1140/epje/i2003-10153-0); `c` = 0.05 of it is 16 mm/s at `s` = 10 mm and
//! `g` = 9.81 m/s², a grain moving a twentieth of its size in the time it takes to fall
//! one size. A heap creeping at that speed moves its surface by `c √(g s) T_angle`, 1.6
//! spacings in the angle's window: 0.3° is the change in the angle such a creep may leave
//! on a flank of 40 spacings (`atan(1.6 / 40)` is 2.3°, so 0.3° asks for about an eighth
//! of it) and is about a tenth of the ±2–4° scatter of measured angles of repose. The
//! figures are the defaults of [`RestSettings`]; every one can be changed there.
//!
//! The verdict ([`RestVerdict`]) carries every quantity judged with its bound and by how
//! much it misses ([`RestMargin`]), how long the speeds have held, and `rest_from_s`: the
//! time of the first sample of the speeds' current hold, when the heap is at rest.
//!
//! Nothing panics on input: an empty set, positions and velocities of different lengths, a
//! non-finite position or velocity, settings out of range, or samples out of time order are
//! a [`MeasureError`].

use std::collections::HashMap;

use crate::repose::PileShape;
use crate::{check_finite, MeasureError};
use sph_core::{Real, Vec3};

const REST: &str = "rest criterion";

/// The figures of the rest criterion (module documentation); the defaults are the criterion
/// as granular codes use it. Parsed with serde (unknown keys are an error; a missing key
/// takes its default).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RestSettings {
    /// `c`: the speed bound is `c √(g s)` (default 0.05).
    pub speed_scale: f64,
    /// The percentile of the speeds judged, in `(0, 1]` (default 0.99).
    pub percentile: f64,
    /// Depth below the local surface, in spacings, from which a particle counts as deep
    /// (default 2).
    pub deep_spacings: f64,
    /// How long (s) both speeds must stay below the bound (default 0.5).
    pub speed_hold_s: f64,
    /// The window (s) over which the angle may move less than `angle_drift_deg`
    /// (default 1).
    pub angle_window_s: f64,
    /// The largest change (degrees, max − min) of the angle over its window, exclusive
    /// (default 0.3); `None` judges the speeds only (a material that is not a heap: a
    /// liquid, a column that has not collapsed).
    pub angle_drift_deg: Option<f64>,
}

impl Default for RestSettings {
    fn default() -> Self {
        Self {
            speed_scale: 0.05,
            percentile: 0.99,
            deep_spacings: 2.0,
            speed_hold_s: 0.5,
            angle_window_s: 1.0,
            angle_drift_deg: Some(0.3),
        }
    }
}

impl RestSettings {
    /// Checks the ranges: every figure finite, `speed_scale`, `deep_spacings` and
    /// `angle_drift_deg` > 0, `percentile` in `(0, 1]`, the two windows ≥ 0.
    pub fn validate(&self) -> Result<(), MeasureError> {
        let bad = |option, value, reason| {
            Err(MeasureError::InvalidOption {
                what: REST,
                option,
                value,
                reason,
            })
        };
        for (name, v) in [
            ("speed_scale", self.speed_scale),
            ("deep_spacings", self.deep_spacings),
            ("angle_drift_deg", self.angle_drift_deg.unwrap_or(1.0)),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, v, "must be finite and > 0");
            }
        }
        if !(self.percentile.is_finite() && self.percentile > 0.0 && self.percentile <= 1.0) {
            return bad("percentile", self.percentile, "must be in (0, 1]");
        }
        for (name, v) in [
            ("speed_hold_s", self.speed_hold_s),
            ("angle_window_s", self.angle_window_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, v, "must be finite and >= 0 (s)");
            }
        }
        Ok(())
    }

    /// The speed bound `c √(g s)` (m/s) for gravity `gravity_m_s2` (its magnitude) and
    /// spacing `spacing_m`; errors if either is not finite and > 0.
    pub fn speed_bound_m_s(&self, gravity_m_s2: f64, spacing_m: f64) -> Result<f64, MeasureError> {
        self.validate()?;
        positive("gravity_m_s2", gravity_m_s2)?;
        positive("spacing_m", spacing_m)?;
        Ok(self.speed_scale * (gravity_m_s2 * spacing_m).sqrt())
    }
}

fn positive(option: &'static str, value: f64) -> Result<(), MeasureError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(MeasureError::InvalidOption {
            what: REST,
            option,
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// One frame's figures of the rest criterion.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RestSample {
    /// Time (s).
    pub time_s: f64,
    /// The percentile speed of the heap's particles (m/s).
    #[serde(deserialize_with = "f64_or_nan")]
    pub percentile_speed_m_s: f64,
    /// The largest speed of the particles at least `deep_spacings` below their column's
    /// surface (m/s); 0 if there is none.
    #[serde(deserialize_with = "f64_or_nan")]
    pub deep_max_speed_m_s: f64,
    /// How many particles are that deep.
    pub deep_particles: usize,
    /// The heap's angle (degrees), `None` if it could not be measured.
    pub angle_deg: Option<f64>,
}

/// A number, or `NaN` for `null` (JSON writes a non-finite number as `null`: the sample
/// of a diverged state reads back as not at rest).
fn f64_or_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(<Option<f64> as serde::Deserialize>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// The rest criterion's sample of a heap at `time_s` (module documentation): its particles
/// at `positions` moving with `velocities`, spacing `spacing_m`, columns as `shape` says
/// (the axis of a conical pile does not matter: its cells are square in `(x, z)`), the
/// angle measured by the caller.
///
/// Errors: no particles; lengths that differ; a non-finite position or velocity (the first,
/// with its index); a spacing or time that is not finite, or settings out of range; more
/// than 10⁸ columns along `x` (a spacing far too small for the heap).
pub fn rest_sample<R: Real>(
    positions: &[Vec3<R>],
    velocities: &[Vec3<R>],
    spacing_m: f64,
    shape: PileShape,
    time_s: f64,
    angle_deg: Option<f64>,
    settings: &RestSettings,
) -> Result<RestSample, MeasureError> {
    settings.validate()?;
    positive("spacing_m", spacing_m)?;
    if !time_s.is_finite() {
        return Err(MeasureError::InvalidOption {
            what: REST,
            option: "time_s",
            value: time_s,
            reason: "must be finite",
        });
    }
    check_finite(REST, positions)?;
    if velocities.len() != positions.len() {
        return Err(MeasureError::LengthMismatch {
            what: REST,
            positions: positions.len(),
            velocities: velocities.len(),
        });
    }
    let mut speeds = Vec::new();
    speeds
        .try_reserve_exact(velocities.len())
        .map_err(|_| MeasureError::Degenerate {
            what: REST,
            reason: format!("cannot allocate {} speeds", velocities.len()),
        })?;
    for (index, u) in velocities.iter().enumerate() {
        let s = u.norm().as_f64();
        if !s.is_finite() {
            return Err(MeasureError::NonFiniteVelocity {
                what: REST,
                index,
                x: u.x.as_f64(),
                y: u.y.as_f64(),
                z: u.z.as_f64(),
            });
        }
        speeds.push(s);
    }
    let (deep_max_speed_m_s, deep_particles) =
        deep_max_speed(positions, &speeds, spacing_m, shape, settings.deep_spacings)?;
    let k = percentile_rank(speeds.len(), settings.percentile);
    let (_, p, _) = speeds.select_nth_unstable_by(k, f64::total_cmp);
    Ok(RestSample {
        time_s,
        percentile_speed_m_s: *p,
        deep_max_speed_m_s,
        deep_particles,
        angle_deg: angle_deg.filter(|a| a.is_finite()),
    })
}

/// The 0-based index of the nearest-rank percentile `p` among `n ≥ 1` sorted values:
/// `⌈p n⌉ − 1`, within `[0, n − 1]`.
pub fn percentile_rank(n: usize, p: f64) -> usize {
    let rank = (p * n as f64).ceil() as usize;
    rank.clamp(1, n.max(1)) - 1
}

/// The column of a position: its index along `x` (and `z` for a conical pile) in cells of
/// `spacing_m` from the origin `lo`.
fn column<R: Real>(p: &Vec3<R>, lo: [f64; 2], spacing_m: f64, shape: PileShape) -> (i64, i64) {
    let ix = ((p.x.as_f64() - lo[0]) / spacing_m).floor() as i64;
    let iz = match shape {
        PileShape::Planar => 0,
        PileShape::Conical { .. } => ((p.z.as_f64() - lo[1]) / spacing_m).floor() as i64,
    };
    (ix, iz)
}

/// The largest of `speeds` over the particles at least `deep_spacings · spacing_m` below
/// the highest particle of their column, and how many such particles there are (0 and 0
/// when none is).
fn deep_max_speed<R: Real>(
    positions: &[Vec3<R>],
    speeds: &[f64],
    spacing_m: f64,
    shape: PileShape,
    deep_spacings: f64,
) -> Result<(f64, usize), MeasureError> {
    let lo = positions.iter().fold([f64::INFINITY; 2], |m, p| {
        [m[0].min(p.x.as_f64()), m[1].min(p.z.as_f64())]
    });
    let hi_x = positions
        .iter()
        .map(|p| p.x.as_f64())
        .fold(f64::NEG_INFINITY, f64::max);
    if (hi_x - lo[0]) / spacing_m > 1e8 {
        return Err(MeasureError::InvalidOption {
            what: REST,
            option: "spacing_m",
            value: spacing_m,
            reason: "gives more than 1e8 columns over the particles' extent (too small)",
        });
    }
    let mut top: HashMap<(i64, i64), f64> = HashMap::new();
    for p in positions {
        let y = p.y.as_f64();
        top.entry(column(p, lo, spacing_m, shape))
            .and_modify(|t| *t = t.max(y))
            .or_insert(y);
    }
    // Within a billionth of a spacing: a lattice's rows two spacings apart count as deep.
    let depth = (deep_spacings - 1e-9) * spacing_m;
    let mut out = (0.0f64, 0usize);
    for (p, &s) in positions.iter().zip(speeds) {
        if top[&column(p, lo, spacing_m, shape)] - p.y.as_f64() >= depth {
            out = (out.0.max(s), out.1 + 1);
        }
    }
    Ok(out)
}

/// One quantity of the verdict: its value, its bound, and whether it is within.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RestMargin {
    /// The value judged (for the speeds, the largest over the hold window; for the angle,
    /// max − min over its window; `NaN` when it could not be measured over the window).
    pub value: f64,
    /// The bound it must stay below.
    pub bound: f64,
}

impl RestMargin {
    /// Whether the value is below the bound (a `NaN` value is not).
    pub fn passes(&self) -> bool {
        self.value < self.bound
    }

    /// By how much the value misses its bound: `value − bound` when it is at or above it,
    /// 0 when it passes, infinite when the value could not be measured.
    pub fn misses_by(&self) -> f64 {
        if self.value.is_nan() {
            f64::INFINITY
        } else {
            (self.value - self.bound).max(0.0)
        }
    }
}

/// The verdict of [`judge_rest`] at the last sample.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RestVerdict {
    /// Whether the heap is at rest.
    pub at_rest: bool,
    /// When at rest: the time (s) of the first sample of the speeds' current hold.
    pub rest_from_s: Option<f64>,
    /// The time (s) of the last sample, where the verdict is given.
    pub judged_at_s: f64,
    /// The percentile speed over the hold window (the largest of its samples).
    pub percentile_speed: RestMargin,
    /// The deep particles' largest speed over the hold window.
    pub deep_speed: RestMargin,
    /// The angle's change over its window (degrees); `None` when the settings do not
    /// judge the angle.
    pub angle_drift: Option<RestMargin>,
    /// The angle (degrees) at the last sample, if measured.
    pub angle_deg: Option<f64>,
    /// How long (s) both speeds have stayed below the bound, up to the last sample, against
    /// [`RestSettings::speed_hold_s`].
    pub speeds_held_s: f64,
    /// How much of the angle's window (s) the samples cover, against
    /// [`RestSettings::angle_window_s`].
    pub angle_window_covered_s: f64,
}

/// Judges the heap at the last of `samples` (time order, one per frame; module
/// documentation). `speed_bound_m_s` is [`RestSettings::speed_bound_m_s`] of the run.
///
/// Errors: no samples; settings or a bound out of range; samples out of time order or with
/// non-finite times.
pub fn judge_rest(
    samples: &[RestSample],
    speed_bound_m_s: f64,
    settings: &RestSettings,
) -> Result<RestVerdict, MeasureError> {
    settings.validate()?;
    positive("speed_bound_m_s", speed_bound_m_s)?;
    let last = samples.last().ok_or(MeasureError::Empty {
        what: "rest criterion (no samples)",
    })?;
    for (index, w) in samples.windows(2).enumerate() {
        if !(w[0].time_s.is_finite() && w[1].time_s.is_finite() && w[0].time_s < w[1].time_s) {
            return Err(MeasureError::Degenerate {
                what: REST,
                reason: format!(
                    "samples {index} and {} are not in increasing time order (t = {} s, {} s)",
                    index + 1,
                    w[0].time_s,
                    w[1].time_s
                ),
            });
        }
    }
    let t_end = last.time_s;
    let slow = |s: &RestSample| {
        s.percentile_speed_m_s < speed_bound_m_s && s.deep_max_speed_m_s < speed_bound_m_s
    };
    // The trailing run of slow samples.
    let first_slow = samples.iter().rposition(|s| !slow(s)).map_or(0, |i| i + 1);
    let speeds_held_s = if first_slow < samples.len() {
        t_end - samples[first_slow].time_s
    } else {
        0.0
    };
    // The speeds are judged over the samples of the hold window.
    let t_hold = t_end - settings.speed_hold_s;
    let in_hold = samples.iter().filter(|s| s.time_s >= t_hold - 1e-9);
    let (p_max, d_max) = in_hold.fold((f64::NEG_INFINITY, f64::NEG_INFINITY), |(p, d), s| {
        (p.max(s.percentile_speed_m_s), d.max(s.deep_max_speed_m_s))
    });
    // The angle over its window, which the samples must cover.
    let t_angle = t_end - settings.angle_window_s;
    let angle_window_covered_s = (t_end - samples[0].time_s).min(settings.angle_window_s);
    let angles: Vec<Option<f64>> = samples
        .iter()
        .filter(|s| s.time_s >= t_angle - 1e-9)
        .map(|s| s.angle_deg)
        .collect();
    let covered = samples[0].time_s <= t_angle + 1e-9;
    let drift = if covered && angles.iter().all(Option::is_some) {
        let (lo, hi) = angles
            .iter()
            .flatten()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        hi - lo
    } else {
        f64::NAN
    };
    let percentile_speed = RestMargin {
        value: p_max,
        bound: speed_bound_m_s,
    };
    let deep_speed = RestMargin {
        value: d_max,
        bound: speed_bound_m_s,
    };
    let angle_drift = settings.angle_drift_deg.map(|bound| RestMargin {
        value: drift,
        bound,
    });
    let held = speeds_held_s >= settings.speed_hold_s - 1e-9 && first_slow < samples.len();
    let at_rest = held
        && percentile_speed.passes()
        && deep_speed.passes()
        && angle_drift.is_none_or(|a| a.passes());
    Ok(RestVerdict {
        at_rest,
        rest_from_s: at_rest.then(|| samples[first_slow].time_s),
        judged_at_s: t_end,
        percentile_speed,
        deep_speed,
        angle_drift,
        angle_deg: last.angle_deg,
        speeds_held_s,
        angle_window_covered_s,
    })
}

impl RestVerdict {
    /// Every quantity judged: `(name, unit, margin)` (the angle's drift only when judged).
    pub fn margins(&self) -> Vec<(&'static str, &'static str, RestMargin)> {
        let mut out = vec![
            ("percentile_speed", "m/s", self.percentile_speed),
            ("deep_speed", "m/s", self.deep_speed),
        ];
        if let Some(a) = self.angle_drift {
            out.push(("angle_drift", "deg", a));
        }
        out
    }

    /// One line saying the verdict and, when not at rest, what misses and by how much.
    pub fn summary(&self, settings: &RestSettings) -> String {
        let mut misses = Vec::new();
        for (name, unit, r) in self.margins() {
            if r.value.is_nan() {
                misses.push(format!(
                    "{name} not measured over its window (bound {:.4} {unit})",
                    r.bound
                ));
            } else if !r.passes() {
                misses.push(format!(
                    "{name} {:.4} {unit} >= {:.4} {unit} (misses by {:.4} {unit})",
                    r.value,
                    r.bound,
                    r.misses_by()
                ));
            }
        }
        if self.speeds_held_s < settings.speed_hold_s - 1e-9 {
            misses.push(format!(
                "speeds below the bound for {:.3} s of {} s",
                self.speeds_held_s, settings.speed_hold_s
            ));
        }
        if self.angle_drift.is_some()
            && self.angle_window_covered_s < settings.angle_window_s - 1e-9
        {
            misses.push(format!(
                "angle window covered {:.3} s of {} s",
                self.angle_window_covered_s, settings.angle_window_s
            ));
        }
        let drift = self.angle_drift.map_or(String::new(), |a| {
            format!(", angle drift {:.3} deg", a.value)
        });
        match (self.at_rest, self.rest_from_s) {
            (true, Some(t)) => format!(
                "at rest at t = {:.3} s (speeds below {:.4} m/s since t = {t:.3} s{drift})",
                self.judged_at_s, self.percentile_speed.bound
            ),
            _ => format!(
                "not at rest at t = {:.3} s: {}",
                self.judged_at_s,
                misses.join("; ")
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t: f64, p: f64, d: f64, a: Option<f64>) -> RestSample {
        RestSample {
            time_s: t,
            percentile_speed_m_s: p,
            deep_max_speed_m_s: d,
            deep_particles: 1,
            angle_deg: a,
        }
    }

    /// Samples every 0.05 s from 0 to `t_end`.
    fn series(t_end: f64, f: impl Fn(f64) -> (f64, f64, Option<f64>)) -> Vec<RestSample> {
        (0..=((t_end / 0.05).round() as usize))
            .map(|i| {
                let t = i as f64 * 0.05;
                let (p, d, a) = f(t);
                sample(t, p, d, a)
            })
            .collect()
    }

    #[test]
    fn the_default_settings_are_the_criterion_of_granular_codes() {
        let s = RestSettings::default();
        assert_eq!(
            (s.speed_scale, s.percentile, s.deep_spacings),
            (0.05, 0.99, 2.0)
        );
        assert_eq!(
            (s.speed_hold_s, s.angle_window_s, s.angle_drift_deg),
            (0.5, 1.0, Some(0.3))
        );
        let b = s.speed_bound_m_s(9.81, 0.01).unwrap();
        assert!((b - 0.05 * (0.0981f64).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn settings_parse_with_defaults_and_reject_unknown_keys() {
        let s: RestSettings = serde_json::from_str(r#"{"speed_hold_s": 0.25}"#).unwrap();
        assert_eq!(s.speed_hold_s, 0.25);
        assert_eq!(s.angle_drift_deg, Some(0.3));
        let s: RestSettings = serde_json::from_str(r#"{"angle_drift_deg": null}"#).unwrap();
        assert_eq!(s.angle_drift_deg, None);
        assert!(serde_json::from_str::<RestSettings>(r#"{"hold": 1}"#).is_err());
        let bad = RestSettings {
            percentile: 1.5,
            ..RestSettings::default()
        };
        assert!(matches!(
            bad.validate(),
            Err(MeasureError::InvalidOption {
                option: "percentile",
                ..
            })
        ));
    }

    #[test]
    fn a_sample_of_a_diverged_state_reads_back_as_not_slow() {
        let s = sample(0.5, f64::NAN, 0.0, None);
        let json = serde_json::to_string(&s).unwrap();
        let back: RestSample = serde_json::from_str(&json).unwrap();
        assert!(back.percentile_speed_m_s.is_nan() && back.time_s == 0.5);
    }

    #[test]
    fn a_still_heap_is_at_rest_from_the_start_of_its_hold() {
        let s = RestSettings::default();
        let v = judge_rest(&series(1.5, |_| (0.001, 0.001, Some(30.0))), 0.0157, &s).unwrap();
        assert!(v.at_rest, "{v:?}");
        assert_eq!(v.rest_from_s, Some(0.0));
        assert_eq!(v.percentile_speed.misses_by(), 0.0);
    }

    #[test]
    fn a_fast_frame_inside_the_hold_restarts_it_and_the_margin_says_by_how_much() {
        let s = RestSettings::default();
        let samples = series(1.5, |t| {
            let p = if (t - 1.2).abs() < 1e-9 { 0.02 } else { 0.001 };
            (p, 0.001, Some(30.0))
        });
        let v = judge_rest(&samples, 0.0157, &s).unwrap();
        assert!(!v.at_rest);
        assert!((v.percentile_speed.misses_by() - (0.02 - 0.0157)).abs() < 1e-12);
        assert!((v.speeds_held_s - 0.25).abs() < 1e-9, "{}", v.speeds_held_s);
        assert!(
            v.summary(&s).contains("percentile_speed 0.0200 m/s"),
            "{}",
            v.summary(&s)
        );
        // Later, the hold has lasted 0.5 s again: at rest from the first slow sample.
        let samples = series(1.75, |t| {
            let p = if (t - 1.2).abs() < 1e-9 { 0.02 } else { 0.001 };
            (p, 0.001, Some(30.0))
        });
        let v = judge_rest(&samples, 0.0157, &s).unwrap();
        assert!(v.at_rest, "{v:?}");
        assert!((v.rest_from_s.unwrap() - 1.25).abs() < 1e-9);
    }

    #[test]
    fn a_creeping_slab_under_a_still_surface_is_not_at_rest() {
        let s = RestSettings::default();
        let v = judge_rest(&series(2.0, |_| (0.001, 0.03, Some(30.0))), 0.0157, &s).unwrap();
        assert!(!v.at_rest);
        assert!(v.percentile_speed.passes() && !v.deep_speed.passes());
        assert!((v.deep_speed.misses_by() - (0.03 - 0.0157)).abs() < 1e-12);
    }

    #[test]
    fn a_turning_angle_or_a_short_or_unmeasured_window_is_not_rest() {
        let s = RestSettings::default();
        // 0.4°/s: 0.4° over the last second.
        let v = judge_rest(
            &series(2.0, |t| (0.001, 0.001, Some(30.0 + 0.4 * t))),
            0.0157,
            &s,
        )
        .unwrap();
        assert!(!v.at_rest);
        let a = v.angle_drift.unwrap();
        assert!((a.value - 0.4).abs() < 1e-9);
        assert!((a.misses_by() - 0.1).abs() < 1e-9);
        assert!(
            v.summary(&s).contains("angle_drift 0.4000 deg"),
            "{}",
            v.summary(&s)
        );
        // 0.2°/s passes.
        let v = judge_rest(
            &series(2.0, |t| (0.001, 0.001, Some(30.0 + 0.2 * t))),
            0.0157,
            &s,
        )
        .unwrap();
        assert!(v.at_rest);
        // Less than a second of samples.
        let v = judge_rest(&series(0.9, |_| (0.0, 0.0, Some(30.0))), 0.0157, &s).unwrap();
        assert!(!v.at_rest && v.angle_drift.unwrap().value.is_nan());
        assert!((v.angle_window_covered_s - 0.9).abs() < 1e-9);
        assert_eq!(v.angle_drift.unwrap().misses_by(), f64::INFINITY);
        // Without the angle judged, the speeds alone decide.
        let speeds_only = RestSettings {
            angle_drift_deg: None,
            ..s
        };
        let v = judge_rest(&series(0.9, |_| (0.0, 0.0, None)), 0.0157, &speeds_only).unwrap();
        assert!(v.at_rest && v.angle_drift.is_none());
        // An angle missing in the window.
        let v = judge_rest(
            &series(2.0, |t| (0.0, 0.0, (t < 1.5).then_some(30.0))),
            0.0157,
            &s,
        )
        .unwrap();
        assert!(!v.at_rest);
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let s = RestSettings::default();
        let x = [Vec3::new(0.0, 0.0, 0.0)];
        let nan = [Vec3::new(f64::NAN, 0.0, 0.0)];
        let r = |p: &[Vec3<f64>], v: &[Vec3<f64>]| {
            rest_sample(p, v, 0.01, PileShape::Planar, 0.0, None, &s)
        };
        assert!(matches!(r(&[], &[]), Err(MeasureError::Empty { .. })));
        assert!(matches!(r(&nan, &x), Err(MeasureError::NonFinite { .. })));
        assert!(matches!(
            r(&x, &nan),
            Err(MeasureError::NonFiniteVelocity { index: 0, .. })
        ));
        assert!(matches!(
            r(&x, &[]),
            Err(MeasureError::LengthMismatch { .. })
        ));
        assert!(rest_sample(&x, &x, f64::NAN, PileShape::Planar, 0.0, None, &s).is_err());
        assert!(judge_rest(&[], 0.01, &s).is_err());
        let a = sample(1.0, 0.0, 0.0, None);
        assert!(judge_rest(&[a, a], 0.01, &s).is_err());
        assert!(judge_rest(&[sample(f64::NAN, 0.0, 0.0, None), a], 0.01, &s).is_err());
        assert!(judge_rest(&[a], -1.0, &s).is_err());
    }

    #[test]
    fn a_column_of_particles_has_its_deep_ones_two_spacings_down() {
        let s = RestSettings::default();
        // One column of 5 particles, spacing 0.01: the bottom three are ≥ 2 s deep.
        let x: Vec<Vec3<f64>> = (0..5)
            .map(|j| Vec3::new(0.0, j as f64 * 0.01, 0.0))
            .collect();
        let v: Vec<Vec3<f64>> = (0..5).map(|j| Vec3::new(j as f64, 0.0, 0.0)).collect();
        let r = rest_sample(&x, &v, 0.01, PileShape::Planar, 0.0, Some(1.0), &s).unwrap();
        assert_eq!(r.deep_particles, 3);
        assert_eq!(r.deep_max_speed_m_s, 2.0);
        assert_eq!(r.percentile_speed_m_s, 4.0); // ⌈0.99 · 5⌉ = 5th smallest
    }
}
