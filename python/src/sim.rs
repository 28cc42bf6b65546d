//! `sph-sim`: a scene run frame by frame through the workspace's one frame loop.

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use sph_core::{Real, Vec3};
use sph_sim::run::ProgressObserver;
use sph_sim::{
    run_frames, Ending, Flow, FrameObserver, FrameRecord, RunOutcome, RunPlan, Scene, SceneSim,
    SimError,
};

use crate::rust_err;

/// A scene in either precision (the scene file's `precision`).
enum AnySim {
    F32(SceneSim<f32>),
    F64(SceneSim<f64>),
}

macro_rules! each {
    ($sim:expr, $s:ident => $e:expr) => {
        match $sim {
            AnySim::F32($s) => $e,
            AnySim::F64($s) => $e,
        }
    };
}

/// A scene being simulated (`SceneSim`): `step()` advances one frame, `run(frames)` many.
#[pyclass(module = "partisim")]
struct Simulation {
    sim: Mutex<AnySim>,
    record: Option<FrameRecord>,
}

/// The frame record as a Python dict: its serde form (`phases_s` a dict by phase name).
fn record_dict<'py>(py: Python<'py>, r: &FrameRecord) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_string(r).map_err(rust_err)?;
    py.import("json")?.call_method1("loads", (json,))
}

/// Python's side of a run: Ctrl-C (a pending signal) and the caller's callback, asked
/// after each frame; the first Python error (KeyboardInterrupt, or the callback's) is kept
/// and ends the run.
struct PythonSide {
    callback: Option<Py<PyAny>>,
    err: Option<PyErr>,
    last: Option<FrameRecord>,
}

impl PythonSide {
    fn ask(&mut self, py: Python<'_>, record: &FrameRecord) -> PyResult<Flow> {
        py.check_signals()?;
        let Some(cb) = &self.callback else {
            return Ok(Flow::Continue);
        };
        let answer = cb.call1(py, (record_dict(py, record)?,))?;
        let answer = answer.bind(py);
        if answer.is_none() || answer.is_truthy()? && !answer.is_instance_of::<PyString>() {
            return Ok(Flow::Continue);
        }
        Ok(Flow::Stop(match answer.extract::<String>() {
            Ok(reason) => reason,
            Err(_) => "stopped by the callback".into(),
        }))
    }
}

impl<R: Real> FrameObserver<R> for PythonSide {
    fn frame(&mut self, _: &SceneSim<R>, record: &FrameRecord) -> Result<Flow, SimError> {
        self.last = Some(*record);
        match Python::attach(|py| self.ask(py, record)) {
            Ok(flow) => Ok(flow),
            Err(e) => {
                self.err = Some(e);
                Ok(Flow::Interrupt)
            }
        }
    }
}

fn run_in<R: Real>(
    sim: &mut SceneSim<R>,
    frames: usize,
    progress: bool,
    side: &mut PythonSide,
) -> Result<RunOutcome, SimError> {
    let plan = RunPlan::next(sim, frames);
    let mut bar = ProgressObserver::new(progress);
    run_frames(sim, &plan, &mut [&mut bar, side])
}

/// How a run ended, as a dict: `ending` ("completed", "stopped" or "diverged"), `frame`,
/// `time_s`, `reason` (the stop's or the divergence's, else None).
fn outcome_dict<'py>(py: Python<'py>, o: &RunOutcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("ending", o.ending.name())?;
    d.set_item("frame", o.frame)?;
    d.set_item("time_s", o.time_s)?;
    d.set_item("reason", o.ending.reason())?;
    Ok(d)
}

/// Per-particle vectors in the scene's order, as an (N, 3) array of the scene's precision.
fn array2<'py, R: Real + numpy::Element>(
    py: Python<'py>,
    sim: &SceneSim<R>,
    v: &[Vec3<R>],
) -> PyResult<Bound<'py, PyAny>> {
    let ordered = sim.to_original_order(v).map_err(rust_err)?;
    let flat: Vec<R> = ordered.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    Ok(flat
        .into_pyarray(py)
        .reshape([ordered.len(), 3])?
        .into_any())
}

impl Simulation {
    fn lock(&self) -> std::sync::MutexGuard<'_, AnySim> {
        self.sim.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Runs `frames` frames with the GIL released; a Python error (Ctrl-C, the callback's)
    /// is raised after the frames done are kept.
    fn run_frames(
        &mut self,
        py: Python<'_>,
        frames: usize,
        progress: bool,
        callback: Option<Py<PyAny>>,
    ) -> PyResult<RunOutcome> {
        let sim = &self.sim;
        let mut side = PythonSide {
            callback,
            err: None,
            last: None,
        };
        let result = py.detach(|| {
            let mut guard = sim.lock().unwrap_or_else(|p| p.into_inner());
            each!(&mut *guard, s => run_in(s, frames, progress, &mut side))
        });
        if side.last.is_some() {
            self.record = side.last;
        }
        if let Some(e) = side.err {
            return Err(e);
        }
        result.map_err(rust_err)
    }
}

#[pymethods]
impl Simulation {
    /// Loads and checks a scene file and builds its particles, boundary and solver.
    #[staticmethod]
    #[pyo3(signature = (path, quick = false))]
    fn from_scene(py: Python<'_>, path: PathBuf, quick: bool) -> PyResult<Self> {
        let sim = py.detach(|| -> Result<AnySim, SimError> {
            let scene = Scene::load(&path)?;
            let scene = if quick { scene.quick() } else { scene };
            Ok(match scene.precision {
                sph_sim::Precision::F32 => AnySim::F32(SceneSim::new(&scene)?),
                sph_sim::Precision::F64 => AnySim::F64(SceneSim::new(&scene)?),
            })
        });
        Ok(Self {
            sim: Mutex::new(sim.map_err(rust_err)?),
            record: None,
        })
    }

    /// Advances one frame (the scene's frame interval) through the frame loop; returns the
    /// frame's statistics. A blow-up raises PartisimError naming the frame, step and
    /// particle (the state keeps its last good substep).
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let outcome = self.run_frames(py, 1, false, None)?;
        if let Ending::Diverged(_) = outcome.ending {
            return Err(rust_err(outcome.ending.reason().unwrap_or_default()));
        }
        match &self.record {
            Some(r) => record_dict(py, r),
            None => Err(rust_err("no frame was advanced")),
        }
    }

    /// Advances `frames` frames through the frame loop, with a progress bar on stderr if
    /// `progress`. `callback(stats)`, if given, is called after each frame with its
    /// statistics (the dict of `stats`); returning False or a string stops the run after
    /// that frame (the string is the reason). Returns how the run ended, a dict with
    /// `ending` ("completed", "stopped" or "diverged": a blow-up is a result, the state
    /// keeps its last good substep), `frame`, `time_s` and `reason`. Ctrl-C stops it
    /// between frames with KeyboardInterrupt, and an exception of the callback ends it
    /// with that exception; the frames done are kept either way.
    #[pyo3(signature = (frames, progress = true, callback = None))]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        frames: usize,
        progress: bool,
        callback: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let outcome = self.run_frames(py, frames, progress, callback)?;
        outcome_dict(py, &outcome)
    }

    /// Positions (m), shape (N, 3), in the scene's particle order and precision.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&*self.lock(), s => array2(py, s, &s.state.positions))
    }

    /// Velocities (m/s), shape (N, 3), in the scene's particle order and precision.
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&*self.lock(), s => array2(py, s, &s.state.velocities))
    }

    /// Densities (kg/m³), shape (N,), in the scene's particle order and precision.
    #[getter]
    fn densities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&*self.lock(), s => Ok(s
            .to_original_order(&s.state.densities)
            .map_err(rust_err)?
            .into_pyarray(py)
            .into_any()))
    }

    /// Simulated time (s).
    #[getter]
    fn time(&self) -> f64 {
        each!(&*self.lock(), s => s.time_s)
    }

    /// Frames done.
    #[getter]
    fn frame(&self) -> usize {
        each!(&*self.lock(), s => s.frame)
    }

    /// The scene's precision, "f32" or "f64".
    #[getter]
    fn precision(&self) -> &'static str {
        match &*self.lock() {
            AnySim::F32(_) => "f32",
            AnySim::F64(_) => "f64",
        }
    }

    /// The last frame's statistics (the frame loop's record) as a dict, or None before the
    /// first frame.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.record.as_ref().map(|r| record_dict(py, r)).transpose()
    }

    /// Writes the particles as a legacy VTK frame (the format of `cargo xtask run`).
    fn write_vtk(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let sim = &self.sim;
        py.detach(|| {
            let guard = sim.lock().unwrap_or_else(|p| p.into_inner());
            each!(&*guard, s => s.write_vtk(&path))
        })
        .map_err(rust_err)
    }

    /// The current particles rendered with the scene's `[render]` settings (the image
    /// `cargo xtask run --render` writes), as an (H, W, 3) uint8 array.
    fn render<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray3<u8>>> {
        let sim = &self.sim;
        let image = py.detach(|| {
            let guard = sim.lock().unwrap_or_else(|p| p.into_inner());
            each!(&*guard, s => sph_sim::render::render_params(&s.scene)
                .and_then(|params| crate::render::render_image(&params, &s.state.positions)
                    .map_err(|e| SimError::Invalid(e.to_string()))))
        });
        crate::render::to_numpy(py, image.map_err(rust_err)?)
    }

    fn __repr__(&self) -> String {
        each!(&*self.lock(), s => format!("{s:?}"))
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Simulation>()
}
