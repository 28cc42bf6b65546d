//! `sph-sim`: a scene run frame by frame through the workspace's one frame loop.

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sph_core::{Real, Vec3};
use sph_sim::run::ProgressObserver;
use sph_sim::{run_frames, FrameObserver, RunPlan, Scene, SceneSim, SimError};
use sph_solver::StepStats;

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
    stats: Option<StepStats>,
}

/// Stops the frame loop when Python has a pending signal (Ctrl-C), keeping the error.
struct Interrupt {
    err: Option<PyErr>,
}

impl<R: Real> FrameObserver<R> for Interrupt {
    fn frame(&mut self, _: &SceneSim<R>, _: &StepStats) -> Result<(), SimError> {
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => Ok(()),
            Err(e) => {
                self.err = Some(e);
                Err(SimError::Invalid("interrupted".into()))
            }
        }
    }
}

/// Keeps the last frame's statistics.
struct LastStats(Option<StepStats>);

impl<R: Real> FrameObserver<R> for LastStats {
    fn frame(&mut self, _: &SceneSim<R>, stats: &StepStats) -> Result<(), SimError> {
        self.0 = Some(*stats);
        Ok(())
    }
}

fn run_in<R: Real>(
    sim: &mut SceneSim<R>,
    frames: usize,
    progress: bool,
) -> (Result<(), SimError>, Option<StepStats>, Option<PyErr>) {
    let plan = RunPlan {
        first_frame: sim.frame,
        last_frame: sim.frame + frames,
        resumed: false,
    };
    let mut bar = ProgressObserver::new(progress);
    let mut last = LastStats(None);
    let mut interrupt = Interrupt { err: None };
    let result = run_frames(sim, &plan, &mut [&mut bar, &mut last, &mut interrupt]);
    (result, last.0, interrupt.err)
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
            stats: None,
        })
    }

    /// Advances one frame (the scene's frame interval); returns the frame's statistics.
    fn step(&mut self, py: Python<'_>) -> PyResult<Py<PyDict>> {
        let sim = &self.sim;
        let stats = py.detach(|| {
            let mut guard = sim.lock().unwrap_or_else(|p| p.into_inner());
            each!(&mut *guard, s => s.advance())
        });
        self.stats = Some(stats.map_err(rust_err)?);
        self.stats(py).map(|s| s.expect("just set"))
    }

    /// Advances `frames` frames through the frame loop, with a progress bar on stderr if
    /// `progress`; Ctrl-C stops it between frames (the frames done are kept).
    #[pyo3(signature = (frames, progress = true))]
    fn run(&mut self, py: Python<'_>, frames: usize, progress: bool) -> PyResult<()> {
        let sim = &self.sim;
        let (result, last, interrupted) = py.detach(|| {
            let mut guard = sim.lock().unwrap_or_else(|p| p.into_inner());
            each!(&mut *guard, s => run_in(s, frames, progress))
        });
        if last.is_some() {
            self.stats = last;
        }
        if let Some(e) = interrupted {
            return Err(e);
        }
        result.map_err(rust_err)
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

    /// The last frame's statistics (`StepStats`) as a dict, or None before the first frame.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Py<PyDict>>> {
        let Some(s) = &self.stats else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("substeps", s.substeps)?;
        d.set_item("iterations", s.iterations)?;
        d.set_item("unconverged_substeps", s.unconverged_substeps)?;
        d.set_item("last_solve_error", s.last_solve_error)?;
        d.set_item("friction_iterations", s.friction_iterations)?;
        d.set_item(
            "unconverged_friction_substeps",
            s.unconverged_friction_substeps,
        )?;
        d.set_item("last_friction_residual", s.last_friction_residual)?;
        d.set_item("neighbour_pairs", s.neighbour_pairs)?;
        d.set_item("max_density_ratio", s.max_density_ratio)?;
        d.set_item("mean_density_ratio", s.mean_density_ratio)?;
        d.set_item("kinetic_energy_j", s.kinetic_energy)?;
        d.set_item("reordered", s.reordered)?;
        let phases = PyDict::new(py);
        for (name, secs) in s.phases.iter() {
            phases.set_item(name, secs)?;
        }
        d.set_item("phases_s", phases)?;
        d.set_item("total_s", s.total_s())?;
        Ok(Some(d.unbind()))
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
