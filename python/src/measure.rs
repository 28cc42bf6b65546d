//! `granular-measure` from Python: the angle of repose of a simulation's particles, with
//! the at-rest verdict of the run that brought them there.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use granular_measure::{angle_of_repose, PileShape, ReposeOptions};
use sph_core::{Aabb, Real, Vec3};
use sph_sim::observe::{RestCriterion, RestObserver};

use crate::rust_err;

/// The rest observer of `run(until_rest=...)` at simulated time `now_s` (s): a dict with
/// `speed_m_s` (> 0), `hold_s` (>= 0), optionally `region`, a pair of corners
/// `((x0, y0, z0), (x1, y1, z1))` (m), and optionally `below_since_s`, the start of a hold
/// under way (an earlier run's `rest_below_since_s`, at most `now_s`).
pub(crate) fn rest_observer(arg: &Bound<'_, PyAny>, now_s: f64) -> PyResult<RestObserver> {
    let d = arg.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err(
            "until_rest: expected a dict with speed_m_s, hold_s and optionally region, below_since_s",
        )
    })?;
    for key in d.keys() {
        let k: String = key.extract()?;
        if !["speed_m_s", "hold_s", "region", "below_since_s"].contains(&k.as_str()) {
            return Err(PyValueError::new_err(format!(
                "until_rest: unknown key {k:?} (the keys are speed_m_s, hold_s, region, below_since_s)"
            )));
        }
    }
    let number = |key: &str| -> PyResult<f64> {
        let v = d
            .get_item(key)?
            .ok_or_else(|| PyValueError::new_err(format!("until_rest: {key} is required")))?;
        v.extract::<f64>()
            .map_err(|_| PyTypeError::new_err(format!("until_rest: {key} must be a number")))
    };
    let speed_m_s = number("speed_m_s")?;
    let hold_s = number("hold_s")?;
    if !(speed_m_s.is_finite() && speed_m_s > 0.0) {
        return Err(PyValueError::new_err(format!(
            "until_rest: speed_m_s = {speed_m_s} must be finite and > 0 (m/s)"
        )));
    }
    if !(hold_s.is_finite() && hold_s >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "until_rest: hold_s = {hold_s} must be finite and >= 0 (s)"
        )));
    }
    let region = match d.get_item("region")?.filter(|r| !r.is_none()) {
        None => None,
        Some(r) => {
            let (lo, hi): ([f64; 3], [f64; 3]) = r.extract().map_err(|_| {
                PyTypeError::new_err("until_rest: region must be ((x0, y0, z0), (x1, y1, z1)) in m")
            })?;
            let b = Aabb::new(Vec3::from(lo), Vec3::from(hi))
                .map_err(|e| PyValueError::new_err(format!("until_rest: region: {e}")))?;
            Some(b)
        }
    };
    let below_since_s = match d.get_item("below_since_s")?.filter(|v| !v.is_none()) {
        None => None,
        Some(v) => {
            let t: f64 = v.extract().map_err(|_| {
                PyTypeError::new_err("until_rest: below_since_s must be a number (s) or None")
            })?;
            if !(t.is_finite() && t <= now_s) {
                return Err(PyValueError::new_err(format!(
                    "until_rest: below_since_s = {t} s must be finite and at most the \
                     simulation's time, {now_s} s (a hold that started before this run)"
                )));
            }
            Some(t)
        }
    };
    let criterion = RestCriterion {
        speed_m_s,
        hold_s,
        region,
    };
    Ok(RestObserver::resumed(criterion, below_since_s))
}

/// The at-rest verdict of the last run watched with a rest criterion.
#[derive(Debug, Clone)]
pub(crate) struct RestVerdict {
    pub criterion: RestCriterion,
    /// The time from which the criterion held (the run stopped then), `None` if it never
    /// held during the run.
    pub rest_from_s: Option<f64>,
    /// The largest speed in the region at the end of the run's last frame (m/s).
    pub last_speed_m_s: Option<f64>,
    /// The start of the hold under way at the run's end (s), `None` if the last speed was
    /// not below the bound: `until_rest`'s `below_since_s` for a run going on from here.
    pub below_since_s: Option<f64>,
    /// The frame the run ended at.
    pub frame: usize,
}

impl RestVerdict {
    pub fn of(observer: &RestObserver, frame: usize) -> Self {
        Self {
            criterion: observer.criterion,
            rest_from_s: observer.rest_from_s,
            last_speed_m_s: observer.speeds_m_s.last().copied(),
            below_since_s: observer.below_since_s(),
            frame,
        }
    }

    /// Adds `at_rest`, `rest_from_s`, `rest_speed_m_s`, `rest_hold_s`, `rest_checked_at_frame`
    /// `rest_below_since_s` and `max_speed_m_s` to `d`.
    pub fn fill(&self, d: &Bound<'_, PyDict>) -> PyResult<()> {
        d.set_item("at_rest", self.rest_from_s.is_some())?;
        d.set_item("rest_from_s", self.rest_from_s)?;
        d.set_item("rest_speed_m_s", self.criterion.speed_m_s)?;
        d.set_item("rest_hold_s", self.criterion.hold_s)?;
        d.set_item("rest_checked_at_frame", self.frame)?;
        d.set_item("rest_below_since_s", self.below_since_s)?;
        d.set_item("max_speed_m_s", self.last_speed_m_s)?;
        Ok(())
    }
}

/// Options of `Simulation.repose`.
pub(crate) struct ReposeArgs<'a> {
    pub shape: &'a str,
    pub floor_y: Option<f64>,
    pub bin_width_m: Option<f64>,
    pub fit_band: (f64, f64),
    pub min_fit_points: usize,
    pub steepest_run_m: Option<f64>,
}

/// The repose measurement of `positions` (m) of a scene with `spacing` (m) and tank bottom
/// `tank_floor` as a dict.
pub(crate) fn repose_dict<'py, R: Real>(
    py: Python<'py>,
    positions: &[Vec3<R>],
    spacing: f64,
    tank_floor: Option<f64>,
    a: &ReposeArgs<'_>,
) -> PyResult<Bound<'py, PyDict>> {
    let floor = a.floor_y.or(tank_floor).unwrap_or(0.0);
    let bin = a.bin_width_m.unwrap_or(spacing);
    let mut opts = match a.shape {
        "planar" => ReposeOptions::planar(floor, bin),
        "conical" => ReposeOptions::conical(floor, bin),
        other => {
            return Err(PyValueError::new_err(format!(
                "shape = {other:?}: \"planar\" (a heap uniform along z, profile along x) or \"conical\""
            )))
        }
    }
    .with_spacing(spacing);
    opts.fit_band = [a.fit_band.0, a.fit_band.1];
    opts.min_fit_points = a.min_fit_points;
    opts.steepest_run_m = a.steepest_run_m;
    let m = py
        .detach(|| angle_of_repose(positions, &opts))
        .map_err(rust_err)?;
    let d = PyDict::new(py);
    d.set_item("angle_deg", m.angle_deg)?;
    d.set_item("resolution_deg", m.resolution_deg)?;
    d.set_item("steepest_deg", m.steepest_deg)?;
    d.set_item("pile_height_m", m.pile_height_m)?;
    d.set_item("apex_d_m", m.apex_d_m)?;
    let flanks = m
        .flanks
        .iter()
        .map(|f| -> PyResult<Bound<'py, PyDict>> {
            let fd = PyDict::new(py);
            fd.set_item("angle_deg", f.angle_deg)?;
            fd.set_item("points", f.points)?;
            fd.set_item("run_m", f.run_m)?;
            fd.set_item("rms_residual_m", f.rms_residual_m)?;
            fd.set_item("side", f.side)?;
            fd.set_item("steepest_deg", f.steepest_deg)?;
            Ok(fd)
        })
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("flanks", flanks)?;
    let profile: Vec<(f64, f64)> = m.profile.iter().map(|p| (p.d_m, p.y_m)).collect();
    d.set_item("profile_m", profile)?;
    d.set_item("particles", positions.len())?;
    d.set_item("floor_y", floor)?;
    d.set_item("bin_width_m", bin)?;
    d.set_item(
        "shape",
        match opts.shape {
            PileShape::Planar => "planar",
            _ => "conical",
        },
    )?;
    Ok(d)
}
