//! `granular-measure` from Python: the angle of repose of a simulation's particles, with
//! the at-rest verdict (granular_measure's rest criterion, with its margins) of the run
//! that brought them there.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};

use granular_measure::{angle_of_repose, PileShape, ReposeOptions};
use sph_core::{Aabb, Real, Vec3};
use sph_sim::observe::{RestCriterion, RestObserver, RestSample, RestSettings, RestVerdict};

use crate::rust_err;

/// The keys of `until_rest` that are not [`RestSettings`]' own.
const REST_KEYS: [&str; 4] = ["region", "shape", "floor_y", "resume"];

/// The rest observer of `run(until_rest=...)` at simulated time `now_s` (s): `True` (the
/// default criterion) or a dict of [`RestSettings`]' figures (`speed_scale`, `percentile`,
/// `deep_spacings`, `speed_hold_s`, `angle_window_s`, `angle_drift_deg`, the last `None`
/// for the speeds only; parsed by serde, unknown keys refused) and optionally `region`, a
/// pair of corners `((x0, y0, z0), (x1, y1, z1))` (m), `shape` ("planar" or "conical"),
/// `floor_y` (m), and `resume`, an earlier outcome's `rest_state` (its samples end at most
/// at `now_s`).
pub(crate) fn rest_observer(arg: &Bound<'_, PyAny>, now_s: f64) -> PyResult<RestObserver> {
    let py = arg.py();
    if arg.is_instance_of::<PyBool>() && arg.is_truthy()? {
        return Ok(RestObserver::new(RestCriterion::default()));
    }
    let d = arg.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err(
            "until_rest: expected True or a dict (the criterion's figures, and optionally region, shape, floor_y, resume)",
        )
    })?;
    let settings_dict = PyDict::new(py);
    for (key, value) in d.iter() {
        let k: String = key.extract()?;
        if ["speed_m_s", "hold_s", "below_since_s"].contains(&k.as_str()) {
            return Err(PyValueError::new_err(format!(
                "until_rest: {k:?} belonged to the old rule (the single fastest particle); the \
                 criterion is now granular_measure's: speed_scale (the bound is speed_scale * \
                 sqrt(g s)), speed_hold_s, percentile, deep_spacings, angle_window_s, \
                 angle_drift_deg, and resume (an earlier outcome's rest_state) to go on"
            )));
        }
        if !REST_KEYS.contains(&k.as_str()) {
            settings_dict.set_item(key, value)?;
        }
    }
    let json: String = py
        .import("json")?
        .call_method1("dumps", (settings_dict,))?
        .extract()?;
    let settings: RestSettings = serde_json::from_str(&json)
        .map_err(|e| PyValueError::new_err(format!("until_rest: {e}")))?;
    settings
        .validate()
        .map_err(|e| PyValueError::new_err(format!("until_rest: {e}")))?;
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
    let shape = match d.get_item("shape")?.filter(|v| !v.is_none()) {
        None => PileShape::Planar,
        Some(v) => match v.extract::<String>()?.as_str() {
            "planar" => PileShape::Planar,
            "conical" => PileShape::Conical { axis_xz: None },
            other => {
                return Err(PyValueError::new_err(format!(
                    "until_rest: shape = {other:?}: \"planar\" or \"conical\""
                )))
            }
        },
    };
    let floor_y = match d.get_item("floor_y")?.filter(|v| !v.is_none()) {
        None => None,
        Some(v) => Some(v.extract::<f64>().map_err(|_| {
            PyTypeError::new_err("until_rest: floor_y must be a number (m) or None")
        })?),
    };
    let carried: Vec<RestSample> = match d.get_item("resume")?.filter(|v| !v.is_none()) {
        None => Vec::new(),
        Some(v) => {
            let json: String = py.import("json")?.call_method1("dumps", (v,))?.extract()?;
            serde_json::from_str(&json).map_err(|e| {
                PyValueError::new_err(format!(
                    "until_rest: resume must be an earlier outcome's rest_state: {e}"
                ))
            })?
        }
    };
    if let Some(last) = carried.last() {
        if !(last.time_s.is_finite() && last.time_s <= now_s + 1e-9) {
            return Err(PyValueError::new_err(format!(
                "until_rest: resume ends at t = {} s, after the simulation's time, {now_s} s \
                 (its samples must come from a run that ended here)",
                last.time_s
            )));
        }
    }
    let criterion = RestCriterion {
        settings,
        region,
        shape,
        floor_y,
    };
    Ok(RestObserver::resumed(criterion, carried))
}

/// The at-rest verdict of the last run watched with a rest criterion.
#[derive(Debug, Clone)]
pub(crate) struct RestOutcome {
    pub criterion: RestCriterion,
    /// The verdict at the run's last sample (`None` if the run sampled nothing).
    pub verdict: Option<RestVerdict>,
    /// The time from which the criterion held (the run stopped then), `None` if it never
    /// held during the run.
    pub rest_from_s: Option<f64>,
    /// The samples a run going on from here needs (`until_rest`'s `resume`).
    pub carried: Vec<RestSample>,
    /// The start of the speeds' hold under way at the run's end (s).
    pub below_since_s: Option<f64>,
    /// The frame the run ended at.
    pub frame: usize,
}

impl RestOutcome {
    pub fn of(observer: &RestObserver, frame: usize) -> Self {
        Self {
            criterion: observer.criterion,
            verdict: observer.verdict,
            rest_from_s: observer.rest_from_s,
            carried: observer.carried(),
            below_since_s: observer.below_since_s(),
            frame,
        }
    }

    /// Adds the verdict to `d`: `at_rest`, `rest_from_s`, `rest_summary`, `rest_margins`
    /// (per quantity: `value`, `bound`, `passes`, `misses_by`), `rest_speed_m_s` (the speed
    /// bound), `rest_hold_s`, `rest_speeds_held_s`, `rest_angle_deg`,
    /// `rest_checked_at_frame`, `rest_below_since_s` and `rest_state` (for `resume`).
    pub fn fill(&self, d: &Bound<'_, PyDict>) -> PyResult<()> {
        let py = d.py();
        let s = &self.criterion.settings;
        d.set_item("at_rest", self.rest_from_s.is_some())?;
        d.set_item("rest_from_s", self.rest_from_s)?;
        d.set_item("rest_summary", self.verdict.map(|v| v.summary(s)))?;
        let margins = PyDict::new(py);
        if let Some(v) = &self.verdict {
            for (name, unit, m) in v.margins() {
                let md = PyDict::new(py);
                md.set_item("value", m.value)?;
                md.set_item("bound", m.bound)?;
                md.set_item("unit", unit)?;
                md.set_item("passes", m.passes())?;
                md.set_item("misses_by", m.misses_by())?;
                margins.set_item(name, md)?;
            }
        }
        d.set_item("rest_margins", margins)?;
        d.set_item(
            "rest_speed_m_s",
            self.verdict.map(|v| v.percentile_speed.bound),
        )?;
        d.set_item("rest_hold_s", s.speed_hold_s)?;
        d.set_item("rest_speeds_held_s", self.verdict.map(|v| v.speeds_held_s))?;
        d.set_item("rest_angle_deg", self.verdict.and_then(|v| v.angle_deg))?;
        d.set_item("rest_checked_at_frame", self.frame)?;
        d.set_item("rest_below_since_s", self.below_since_s)?;
        let json = serde_json::to_string(&self.carried).map_err(rust_err)?;
        d.set_item(
            "rest_state",
            py.import("json")?.call_method1("loads", (json,))?,
        )?;
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
