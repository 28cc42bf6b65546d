//! `sph-sim`: a scene run frame by frame through the workspace's one frame loop.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyList, PyString, PyTuple};
use sph_core::{Real, Vec3};
use sph_scene::Override;
use sph_sim::saved::{decode_saved, encode_saved, read_saved, SceneSource};
use sph_sim::{
    run_frames, Ending, Flow, FrameObserver, FrameRecord, Precision, RunOutcome, RunPlan, Scene,
    SceneSim, SimError,
};
use sph_solver::boundary::{CacheUse, VolumeMapBuild, VolumeMapCache};

use crate::interrupt::interruptible;
use crate::measure::{repose_dict, rest_observer, ReposeArgs, RestOutcome};
use crate::rust_err;
use sph_sim::observe::RestObserver;

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
    /// The scene file's text with the overrides and quick mode: what `save` keeps.
    source: SceneSource,
    /// The volume-map cache directory used, if any.
    cache_dir: Option<PathBuf>,
    /// The at-rest verdict of the last run watched with `until_rest`.
    rest: Option<RestOutcome>,
}

/// The Python type name of `v`, for a message.
fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_default()
}

/// The command line's default volume-map cache (`particles run`), relative to the current
/// directory.
fn default_cache_dir() -> PathBuf {
    PathBuf::from("target").join("cache").join("volume-maps")
}

/// `volume_map_cache`: True (the default: the command line's directory), a directory, or
/// None/False (no cache).
enum CacheChoice {
    Default,
    Off,
    Dir(PathBuf),
}

impl<'a, 'py> FromPyObject<'a, 'py> for CacheChoice {
    type Error = PyErr;

    fn extract(obj: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if obj.is_none() {
            return Ok(CacheChoice::Off);
        }
        if let Ok(b) = obj.cast::<PyBool>() {
            return Ok(if b.is_true() {
                CacheChoice::Default
            } else {
                CacheChoice::Off
            });
        }
        obj.extract::<PathBuf>().map(CacheChoice::Dir).map_err(|_| {
            PyTypeError::new_err(format!(
                "volume_map_cache: expected a directory (str or os.PathLike), True or None, not {}",
                type_name(&obj)
            ))
        })
    }
}

impl CacheChoice {
    fn dir(self) -> Option<PathBuf> {
        match self {
            CacheChoice::Default => Some(default_cache_dir()),
            CacheChoice::Off => None,
            CacheChoice::Dir(d) => Some(d),
        }
    }
}

/// A Python value as the TOML value of the override of `key`: bool, int (numpy integers
/// too), float, str, a list or tuple (or an array, as its `tolist()`) of those, a dict of
/// those.
fn toml_value(key: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    let py = v.py();
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(toml::Value::Boolean(b.is_true()));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract::<String>()?));
    }
    if let Ok(x) = v.cast::<PyFloat>() {
        return Ok(toml::Value::Float(x.value()));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, item) in d.iter() {
            let k: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!("overrides[{key:?}]: table keys must be str"))
            })?;
            let value = toml_value(&format!("{key}.{k}"), &item)?;
            t.insert(k, value);
        }
        return Ok(toml::Value::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items = v
            .try_iter()?
            .enumerate()
            .map(|(i, item)| toml_value(&format!("{key}[{i}]"), &item?))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(items));
    }
    // numpy scalars and arrays: their Python equivalents (int, float, bool, nested lists).
    if v.hasattr("tolist")? {
        let plain = v.call_method0("tolist")?;
        if !plain.is(v) {
            return toml_value(key, &plain);
        }
    }
    if let Ok(i) = py.import("operator")?.call_method1("index", (v,)) {
        return i.extract::<i64>().map(toml::Value::Integer).map_err(|_| {
            PyValueError::new_err(format!(
                "overrides[{key:?}]: {i} does not fit a TOML integer (64-bit signed)"
            ))
        });
    }
    Err(PyTypeError::new_err(format!(
        "overrides[{key:?}]: a {} is not a scene value (give a bool, int, float, str, list or dict)",
        type_name(v)
    )))
}

/// The overrides dict as [`Override`]s, in the dict's order.
fn overrides_of(arg: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Override>> {
    let Some(arg) = arg.filter(|a| !a.is_none()) else {
        return Ok(Vec::new());
    };
    let d = arg.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err("overrides: expected a dict from a key's dotted path to its value")
    })?;
    d.iter()
        .map(|(k, v)| {
            let key: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "overrides: the keys are dotted paths (str), not {}",
                    type_name(&k)
                ))
            })?;
            let value = toml_value(&key, &v)?;
            Ok(Override::new(key, value))
        })
        .collect()
}

/// Builds the simulation of `scene` (with the volume maps from `cache_dir` when the scene
/// has them, the build stopped when `cancel` is set), and restores `checkpoint` (bytes of
/// the checkpoint format) if given.
fn build(
    scene: &Scene,
    cache_dir: Option<&Path>,
    checkpoint: Option<(&Path, &[u8])>,
    cancel: &AtomicBool,
) -> Result<AnySim, SimError> {
    let cache = match (cache_dir, scene.boundary.model) {
        (Some(dir), sph_scene::BoundaryModel::VolumeMap) => {
            Some(VolumeMapCache::new(dir).map_err(|e| SimError::output(dir, e))?)
        }
        _ => None,
    };
    fn restore<R: Real>(
        mut sim: SceneSim<R>,
        checkpoint: Option<(&Path, &[u8])>,
    ) -> Result<SceneSim<R>, SimError> {
        if let Some((file, bytes)) = checkpoint {
            let c = sph_sim::checkpoint::decode::<R>(bytes)
                .map_err(|reason| SimError::input(file, reason))?;
            sim.restore(c)
                .map_err(|reason| SimError::input(file, reason))?;
        }
        Ok(sim)
    }
    let how = VolumeMapBuild {
        cache: cache.as_ref(),
        cancel: Some(cancel),
    };
    Ok(match scene.precision {
        Precision::F32 => AnySim::F32(restore(SceneSim::with_maps(scene, how)?, checkpoint)?),
        Precision::F64 => AnySim::F64(restore(SceneSim::with_maps(scene, how)?, checkpoint)?),
    })
}

/// Runs `work` (a scene's build) on a thread of its own with a cancellation flag: Ctrl-C
/// sets the flag, waits for the build to stop (within a row of volume-map nodes) and
/// raises KeyboardInterrupt.
fn cancellable<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(&AtomicBool) -> T + Send + 'static,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    let stop = move || flag.store(true, Ordering::Relaxed);
    interruptible(py, &stop, move || work(&cancel))
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
    /// The `partisim.progress` display (`update(n)`), if any.
    progress: Option<Py<PyAny>>,
    /// The rest criterion watched (`run(until_rest=...)`), if any.
    rest: Option<RestObserver>,
    err: Option<PyErr>,
    last: Option<FrameRecord>,
}

impl PythonSide {
    fn ask(&mut self, py: Python<'_>, record: &FrameRecord) -> PyResult<Flow> {
        py.check_signals()?;
        if let Some(bar) = &self.progress {
            bar.call_method1(py, "update", (1,))?;
        }
        let Some(cb) = &self.callback else {
            return Ok(Flow::Continue);
        };
        let answer = cb.call1(py, (record_dict(py, record)?,))?;
        let answer = answer.bind(py);
        // The package's one rule (as `Population.advance`'s): something true stops the run,
        // None or anything false goes on; a (non-empty) string is also the stop's reason.
        if !answer.is_truthy()? {
            return Ok(Flow::Continue);
        }
        Ok(Flow::Stop(match answer.extract::<String>() {
            Ok(reason) => reason,
            Err(_) => "stopped by the callback".into(),
        }))
    }
}

impl<R: Real> FrameObserver<R> for PythonSide {
    fn start(&mut self, sim: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        match &mut self.rest {
            Some(r) => r.start(sim, plan),
            None => Ok(()),
        }
    }

    fn frame(&mut self, sim: &SceneSim<R>, record: &FrameRecord) -> Result<Flow, SimError> {
        self.last = Some(*record);
        let rest = match &mut self.rest {
            Some(r) => r.frame(sim, record)?,
            None => Flow::Continue,
        };
        match Python::attach(|py| self.ask(py, record)) {
            // The rest criterion's stop is the run's result: it wins over the callback's.
            Ok(flow) if matches!(rest, Flow::Continue) => Ok(flow),
            Ok(_) => Ok(rest),
            Err(e) => {
                self.err = Some(e);
                Ok(Flow::Interrupt)
            }
        }
    }
}

fn run_in<R: Real>(
    sim: &mut SceneSim<R>,
    last_frame: usize,
    side: &mut PythonSide,
) -> Result<RunOutcome, SimError> {
    let plan = RunPlan {
        first_frame: sim.frame,
        last_frame: last_frame.max(sim.frame),
        resumed: false,
    };
    run_frames(sim, &plan, &mut [side])
}

/// What a call of `run` asked for and what it will do.
struct FramePlan {
    /// The frame the run stops at.
    last_frame: usize,
    /// The scene's last frame (`duration / frame_dt`, as the command line counts it).
    scene_frames: usize,
    /// Frames asked for (`None`: to the scene's end).
    asked: Option<u128>,
}

impl FramePlan {
    /// The plan of `run(frames)` from frame `now` of a scene of `scene_frames` frames: to
    /// the scene's end, or `frames` more but never past it (the command line's `--frames`
    /// stops there too).
    fn new(frames: Option<&Bound<'_, PyAny>>, now: usize, scene_frames: usize) -> PyResult<Self> {
        let asked = match frames.filter(|f| !f.is_none()) {
            None => None,
            Some(f) => {
                if f.is_instance_of::<PyFloat>() || f.is_instance_of::<PyBool>() {
                    return Err(PyTypeError::new_err(format!(
                        "frames: expected a whole number of frames (int), not {}",
                        type_name(f)
                    )));
                }
                let n = f
                    .py()
                    .import("operator")?
                    .call_method1("index", (f,))
                    .map_err(|_| {
                        PyTypeError::new_err(format!(
                            "frames: expected a whole number of frames (int), not {}",
                            type_name(f)
                        ))
                    })?;
                if n.lt(1)? {
                    return Err(PyValueError::new_err(format!(
                        "frames = {n}: a run needs at least 1 frame (None runs to the scene's end)"
                    )));
                }
                // Larger than any scene: clamped to the scene's end below, never wrapped.
                Some(n.extract::<u128>().unwrap_or(u128::MAX))
            }
        };
        let wanted = match asked {
            None => scene_frames,
            Some(n) => (now as u128).saturating_add(n).min(scene_frames as u128) as usize,
        };
        Ok(Self {
            last_frame: wanted.max(now),
            scene_frames,
            asked,
        })
    }

    /// Whether the run stops short of the frames asked for, at the scene's end.
    fn clamped(&self, now: usize) -> bool {
        self.asked
            .is_some_and(|n| (now as u128).saturating_add(n) > self.scene_frames as u128)
    }
}

/// How a run ended, as a dict: `ending` ("completed", "stopped", "interrupted" or
/// "diverged"), `frame`, `time_s`, `reason` (the stop's or the divergence's, else None),
/// `frames_run`, `scene_frames` and `at_scene_end`.
fn outcome_dict<'py>(
    py: Python<'py>,
    o: &RunOutcome,
    first: usize,
    plan: &FramePlan,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("ending", o.ending.name())?;
    d.set_item("frame", o.frame)?;
    d.set_item("time_s", o.time_s)?;
    let mut reason = o.ending.reason();
    if reason.is_none() && plan.clamped(first) && o.frame == plan.scene_frames {
        reason = Some(format!(
            "the scene ends at frame {} (duration / frame_dt): {} frames asked for from frame {first}, {} run",
            plan.scene_frames,
            plan.asked.unwrap_or_default(),
            o.frame.saturating_sub(first)
        ));
    }
    d.set_item("reason", reason)?;
    d.set_item("frames_run", o.frame.saturating_sub(first))?;
    d.set_item("scene_frames", plan.scene_frames)?;
    d.set_item("at_scene_end", o.frame >= plan.scene_frames)?;
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

    /// Runs to frame `last_frame` with the GIL released; a Python error (Ctrl-C, the
    /// callback's) is raised after the frames done are kept.
    fn run_frames(
        &mut self,
        py: Python<'_>,
        last_frame: usize,
        progress: Option<Py<PyAny>>,
        callback: Option<Py<PyAny>>,
        rest: Option<RestObserver>,
    ) -> PyResult<RunOutcome> {
        let sim = &self.sim;
        let mut side = PythonSide {
            callback,
            progress,
            rest,
            err: None,
            last: None,
        };
        let result = py.detach(|| {
            let mut guard = sim.lock().unwrap_or_else(|p| p.into_inner());
            each!(&mut *guard, s => run_in(s, last_frame, &mut side))
        });
        if let Some(bar) = &side.progress {
            bar.call_method0(py, "close")?;
        }
        if side.last.is_some() {
            self.record = side.last;
        }
        if let Some(r) = &side.rest {
            self.rest = Some(RestOutcome::of(r, self.frame()));
        }
        if let Some(e) = side.err {
            return Err(e);
        }
        result.map_err(rust_err)
    }

    /// A simulation built from `source`, before its first run.
    fn new(sim: AnySim, source: SceneSource, cache_dir: Option<PathBuf>) -> Self {
        Self {
            sim: Mutex::new(sim),
            record: None,
            source,
            cache_dir,
            rest: None,
        }
    }

    fn scene_frames(&self) -> usize {
        each!(&*self.lock(), s => s.scene.frame_count())
    }

    /// The bytes of `save` (the scene source and the checkpoint of the current frame).
    fn to_bytes(&self) -> Vec<u8> {
        each!(&*self.lock(), s => encode_saved(&self.source, s))
    }

    /// The simulation saved in `bytes` (read from `file`, named in messages).
    fn from_saved(
        py: Python<'_>,
        file: &Path,
        bytes: &[u8],
        cache_dir: Option<PathBuf>,
    ) -> PyResult<Self> {
        let (source, checkpoint) =
            decode_saved(bytes).map_err(|reason| rust_err(SimError::input(file, reason)))?;
        let (file, dir, checkpoint) = (file.to_path_buf(), cache_dir.clone(), checkpoint.to_vec());
        let (source, sim) = cancellable(py, move |cancel| -> Result<_, SimError> {
            let scene = source.scene()?;
            let saved = Some((file.as_path(), checkpoint.as_slice()));
            let sim = build(&scene, dir.as_deref(), saved, cancel)?;
            Ok((source, sim))
        })?
        .map_err(rust_err)?;
        Ok(Self::new(sim, source, cache_dir))
    }
}

#[pymethods]
impl Simulation {
    /// Loads and checks a scene file (TOML) and builds its particles, boundary and solver.
    ///
    /// Parameters
    /// ----------
    /// path : str or os.PathLike
    ///     The scene file; mesh paths in it are relative to its directory.
    /// quick : bool
    ///     Apply the scene's ``[quick]`` overrides (coarser, shorter), as ``--quick`` does.
    /// overrides : dict, optional
    ///     Values of the scene file's keys by dotted path, e.g.
    ///     ``{"solver.friction_angle_deg": 33.0, "simulation.duration": 2.0,
    ///     "fluid[0].max": [0.3, 0.4, 0.3]}``, applied to the file's document before it is
    ///     checked: a wrong type, an unknown key (named with the keys its table has) or an
    ///     out-of-range value raises PartisimError at the key, "given as an override".
    ///     Values: bool, int (numpy integers too), float, str, list/tuple/array, dict.
    /// volume_map_cache : True, str, os.PathLike or None
    ///     Where volume maps (``[boundary] model = "volume-map"``) are loaded from and stored:
    ///     ``True`` (default) the command line's cache ``target/cache/volume-maps`` under the
    ///     current directory (``particles run`` run from the same directory shares it), a
    ///     directory, or ``None``/``False`` to build them afresh and keep none.
    ///     ``volume_maps`` says what happened to each map.
    ///
    /// Raises
    /// ------
    /// PartisimError
    ///     The scene is unreadable or refused (the message names the file, the key and the
    ///     line, or "given as an override").
    /// KeyboardInterrupt
    ///     Ctrl-C while the scene is built (a volume map's build stops within a row of its
    ///     nodes; maps completed before it stay in the cache).
    #[staticmethod]
    #[pyo3(signature = (path, quick = false, overrides = None, volume_map_cache = CacheChoice::Default))]
    fn from_scene(
        py: Python<'_>,
        path: PathBuf,
        quick: bool,
        overrides: Option<&Bound<'_, PyAny>>,
        volume_map_cache: CacheChoice,
    ) -> PyResult<Self> {
        let overrides = overrides_of(overrides)?;
        let cache_dir = volume_map_cache.dir();
        let dir = cache_dir.clone();
        let built = cancellable(
            py,
            move |cancel| -> Result<(SceneSource, AnySim), SimError> {
                let (source, scene) = SceneSource::load(&path, overrides, quick)?;
                let sim = build(&scene, dir.as_deref(), None, cancel)?;
                Ok((source, sim))
            },
        )?;
        let (source, sim) = built.map_err(rust_err)?;
        Ok(Self::new(sim, source, cache_dir))
    }

    /// Writes the simulation to ``path``, atomically (a temporary file renamed into place:
    /// an interrupted save leaves the earlier file whole): the scene file's text, the
    /// overrides and quick mode, and the whole state of the current frame (particles in the
    /// scene's precision, the solver's carried state, frame and time). ``Simulation.load``
    /// continues from it bit for bit as if the run had not stopped. Mesh files are read
    /// again from their paths when loaded (a changed mesh is refused).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let bytes = self.to_bytes();
        py.detach(|| sph_sim::checkpoint::write_atomically(&path, &bytes))
            .map_err(rust_err)
    }

    /// The simulation saved by ``save`` at ``path``, continuing bit for bit from the frame
    /// it was saved at. ``volume_map_cache`` as for ``from_scene``. A file that is not a
    /// saved simulation, truncated, corrupt, or written by another version raises
    /// PartisimError naming it.
    #[staticmethod]
    #[pyo3(signature = (path, volume_map_cache = CacheChoice::Default))]
    fn load(py: Python<'_>, path: PathBuf, volume_map_cache: CacheChoice) -> PyResult<Self> {
        let cache_dir = volume_map_cache.dir();
        let bytes = py.detach(|| read_saved(&path)).map_err(rust_err)?;
        Self::from_saved(py, &path, &bytes, cache_dir)
    }

    /// Pickling: the bytes of ``save`` (unpickled with the command line's default
    /// volume-map cache directory when the simulation had a cache, else none).
    #[allow(clippy::type_complexity)]
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>, bool))> {
        let restore = py
            .import("partisim.sim")?
            .getattr("_simulation_from_bytes")?;
        let bytes = PyBytes::new(py, &self.to_bytes());
        Ok((restore, (bytes, self.cache_dir.is_some())))
    }

    /// The simulation of ``bytes`` (``save``'s format); used by pickle.
    #[staticmethod]
    #[pyo3(signature = (data, volume_map_cache = CacheChoice::Default))]
    fn _from_bytes(py: Python<'_>, data: &[u8], volume_map_cache: CacheChoice) -> PyResult<Self> {
        let cache_dir = volume_map_cache.dir();
        Self::from_saved(py, Path::new("<pickle>"), data, cache_dir)
    }

    /// How each solid's volume map was obtained when the simulation was built, in solid
    /// order: ``"built"`` (no cache), ``"loaded"`` (from the cache), ``"stored"`` (built and
    /// written to the cache), ``"replaced"`` (a refused cache file rebuilt), ``"write-failed"``
    /// or ``"uncacheable"``; empty for the collision boundary.
    #[getter]
    fn volume_maps(&self) -> Vec<&'static str> {
        let uses = each!(&*self.lock(), s => s.volume_maps.clone());
        uses.iter()
            .map(|u| match u {
                CacheUse::NoCache => "built",
                CacheUse::Uncacheable => "uncacheable",
                CacheUse::Hit => "loaded",
                CacheUse::Stored => "stored",
                CacheUse::Replaced => "replaced",
                CacheUse::WriteFailed => "write-failed",
                _ => "other",
            })
            .collect()
    }

    /// The scene's last frame, ``ceil(duration / frame_dt)``: where ``run()`` stops, as the
    /// command line does.
    #[getter(scene_frames)]
    fn scene_frames_py(&self) -> usize {
        self.scene_frames()
    }

    /// The scene's solver (``[solver] kind``): ``"pbf"``, ``"pcisph"``, ``"iisph"`` or
    /// ``"granular"`` (granular matter: ``repose()`` measures its heap).
    #[getter]
    fn solver(&self) -> &'static str {
        each!(&*self.lock(), s => s.scene.solver.kind_name())
    }

    /// Advances one frame (the scene's frame interval) through the frame loop; returns the
    /// frame's statistics. A blow-up raises PartisimError naming the frame, step and
    /// particle (the state keeps its last good substep). Unlike ``run``, ``step`` may go
    /// past the scene's last frame.
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let next = self.frame().saturating_add(1);
        let outcome = self.run_frames(py, next, None, None, None)?;
        if let Ending::Diverged(_) = outcome.ending {
            return Err(rust_err(outcome.ending.reason().unwrap_or_default()));
        }
        match &self.record {
            Some(r) => record_dict(py, r),
            None => Err(rust_err("no frame was advanced")),
        }
    }

    /// Runs frames through the frame loop, as the command line counts them.
    ///
    /// Parameters
    /// ----------
    /// frames : int or None
    ///     ``None`` (default): to the scene's last frame (``scene_frames``, i.e.
    ///     ``ceil(duration / frame_dt)``); an int ``>= 1`` (numpy integers too): that many
    ///     more frames, but never past the scene's last frame (``particles run --frames``
    ///     stops there too; the outcome's ``reason`` says so). A huge count is clamped,
    ///     never wrapped.
    /// progress : bool or None
    ///     A progress display (``partisim.progress``: tqdm when installed, a widget in
    ///     Jupyter); ``None`` (default) shows it when stderr is a terminal or in Jupyter.
    /// callback : callable, optional
    ///     ``callback(stats)`` after each frame with its statistics (the dict of ``stats``);
    ///     returning something true (``True``, a non-empty string, ...) stops the run after
    ///     that frame, returning ``None`` or anything false goes on (the rule of
    ///     ``Population.advance`` too). A returned string is the stop's ``reason``; on the
    ///     frame where ``until_rest`` also stops the run, the rest's reason is kept.
    /// until_rest : True or dict, optional
    ///     Stop once the heap is at rest by granular codes' criterion (crate
    ///     ``granular-measure``, module ``rest``): the 99th-percentile speed of its particles
    ///     and the fastest particle two spacings below the local surface under
    ///     ``0.05 sqrt(g s)`` for 0.5 s, and its angle of repose moving less than 0.3° over
    ///     the last second (judged after each frame, and on the run's first state). ``True``
    ///     takes these figures; a dict may change them (``speed_scale``, ``percentile``,
    ///     ``deep_spacings``, ``speed_hold_s``, ``angle_window_s``, ``angle_drift_deg``;
    ///     ``angle_drift_deg=None`` judges the speeds only, for a material that is not a
    ///     heap) and give ``region`` (``((x0, y0, z0), (x1, y1, z1))``, m: the heap's
    ///     particles; default all), ``shape`` ("planar", default, or "conical") and
    ///     ``floor_y`` (m; default the tank's bottom). The outcome then has the verdict,
    ///     and ``repose()`` reports it. A run going on from an earlier one (after a stop, a
    ///     ``save``/``load``) gives ``"resume"``: the earlier outcome's ``rest_state``; it
    ///     then stops where one whole run would. (The old ``speed_m_s``/``hold_s``/
    ///     ``below_since_s`` keys are refused with a message.)
    ///
    /// Returns
    /// -------
    /// dict
    ///     ``ending`` ("completed", "stopped" or "diverged": a blow-up is a result, the state
    ///     keeps its last good substep), ``frame`` (frames done), ``time_s`` (simulated, s),
    ///     ``reason`` (the stop's, the divergence's, or the scene's end when fewer frames
    ///     than asked were run; else None), ``frames_run``, ``scene_frames`` and
    ///     ``at_scene_end``; with ``until_rest``, the verdict: ``at_rest`` (bool),
    ///     ``rest_from_s`` (the start of the speeds' hold when at rest, s), ``rest_summary``
    ///     (one line: what misses and by how much), ``rest_margins`` (per quantity,
    ///     ``percentile_speed``, ``deep_speed`` and ``angle_drift``: ``value``, ``bound``,
    ///     ``unit``, ``passes``, ``misses_by``), ``rest_speed_m_s`` (the speed bound),
    ///     ``rest_hold_s``, ``rest_speeds_held_s``, ``rest_angle_deg``,
    ///     ``rest_below_since_s`` (the start of the speeds' hold under way, s, or None),
    ///     ``rest_checked_at_frame`` and ``rest_state`` (for ``resume``).
    ///
    /// Ctrl-C stops the run between frames with KeyboardInterrupt, and an exception of the
    /// callback ends it with that exception; the frames done are kept either way.
    #[pyo3(signature = (frames = None, progress = None, callback = None, until_rest = None))]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        frames: Option<&Bound<'py, PyAny>>,
        progress: Option<bool>,
        callback: Option<Py<PyAny>>,
        until_rest: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let now_s = self.time();
        let rest = until_rest
            .filter(|r| !r.is_none())
            .map(|r| rest_observer(r, now_s))
            .transpose()?;
        let watched = rest.is_some();
        let first = self.frame();
        let plan = FramePlan::new(frames, first, self.scene_frames())?;
        let total = plan.last_frame - first;
        let bar = py
            .import("partisim.progress")?
            .call_method1("make_progress", (total, progress, "frames"))?;
        let outcome = self.run_frames(py, plan.last_frame, Some(bar.unbind()), callback, rest)?;
        let d = outcome_dict(py, &outcome, first, &plan)?;
        if let Some(v) = self.rest.as_ref().filter(|_| watched) {
            v.fill(&d)?;
        }
        Ok(d)
    }

    /// The angle of repose of the current particles (crate ``granular-measure``: the
    /// free-surface profile binned along ``x`` (planar) or by distance from the axis
    /// (conical), each flank fitted by least squares between ``fit_band`` fractions of the
    /// pile height), with the at-rest verdict of the last ``run(until_rest=...)``.
    ///
    /// Parameters
    /// ----------
    /// shape : "planar" or "conical"
    ///     A heap uniform along ``z`` (profile along ``x``), or a pile around the particles'
    ///     centroid.
    /// floor_y : float, optional
    ///     Height of the floor (m); default the tank's bottom, else 0.
    /// bin_width_m : float, optional
    ///     Width of the profile's bins (m); default the particle spacing.
    /// fit_band : (float, float)
    ///     Fractions of the pile height between which the flanks are fitted.
    /// min_fit_points : int
    ///     Fewest surface points per fitted flank (>= 3).
    /// steepest_run_m : float, optional
    ///     Also report the steepest slope over runs of this length (m).
    ///
    /// Returns
    /// -------
    /// dict
    ///     ``angle_deg`` (mean over the flanks), ``resolution_deg`` (the bound on the error
    ///     from the sampling at this spacing), ``steepest_deg``, ``pile_height_m``,
    ///     ``apex_d_m``, ``flanks`` (per flank: ``angle_deg``, ``points``, ``run_m``,
    ///     ``rms_residual_m``, ``side``), ``profile_m`` (the surface points ``(d, y)``, m),
    ///     ``particles``, ``frame``, ``time_s``, and the verdict: ``at_rest`` (True/False
    ///     from the last run watched with ``until_rest``; None if none was, or if frames were
    ///     run since it ended), with the rest of that run's verdict as ``run`` returns it
    ///     (``rest_summary``, ``rest_margins``: by how much each quantity misses, ...).
    ///
    /// Raises PartisimError for a pile that cannot be measured (flat layer, too few surface
    /// points, options out of range).
    #[pyo3(signature = (shape = "planar", floor_y = None, bin_width_m = None, fit_band = (0.2, 0.8), min_fit_points = 4, steepest_run_m = None))]
    #[allow(clippy::too_many_arguments)]
    fn repose<'py>(
        &self,
        py: Python<'py>,
        shape: &str,
        floor_y: Option<f64>,
        bin_width_m: Option<f64>,
        fit_band: (f64, f64),
        min_fit_points: usize,
        steepest_run_m: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let args = ReposeArgs {
            shape,
            floor_y,
            bin_width_m,
            fit_band,
            min_fit_points,
            steepest_run_m,
        };
        let guard = self.lock();
        let d = each!(&*guard, s => repose_dict(
            py,
            &s.state.positions,
            s.scene.particle_spacing,
            s.scene.tank.as_ref().map(|t| t.min.y),
            &args,
        ))?;
        let (frame, time_s) = each!(&*guard, s => (s.frame, s.time_s));
        drop(guard);
        d.set_item("frame", frame)?;
        d.set_item("time_s", time_s)?;
        match &self.rest {
            Some(v) => {
                v.fill(&d)?;
                if v.frame != frame {
                    d.set_item("at_rest", py.None())?;
                }
            }
            None => d.set_item("at_rest", py.None())?,
        }
        Ok(d)
    }

    /// Positions (m), a new array of shape (N, 3): float32 or float64 as the scene's
    /// ``precision``, row ``k`` the particle the scene created ``k``-th (whatever order the
    /// solver keeps them in), at simulated time ``time``.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&*self.lock(), s => array2(py, s, &s.state.positions))
    }

    /// Velocities (m/s), a new array of shape (N, 3), in the order and precision of
    /// ``positions``.
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&*self.lock(), s => array2(py, s, &s.state.velocities))
    }

    /// Densities (kg/m³) of the last solver step, a new array of shape (N,), in the order
    /// and precision of ``positions``.
    #[getter]
    fn densities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&*self.lock(), s => Ok(s
            .to_original_order(&s.state.densities)
            .map_err(rust_err)?
            .into_pyarray(py)
            .into_any()))
    }

    /// The solver's per-particle fields beside positions, velocities and densities, a new
    /// dict of arrays in the order and precision of ``positions``: for the elastoplastic
    /// solver ``"stress"`` (Pa, shape (N, 6): xx, yy, zz, xy, yz, zx; tension positive) and
    /// ``"plastic_strain"`` (the equivalent plastic shear strain, shape (N,)); empty for
    /// solvers that carry none.
    #[getter]
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        each!(&*self.lock(), s => {
            for (name, k, values) in s.particle_fields().map_err(rust_err)? {
                let n = values.len() / k;
                let a = values.into_pyarray(py);
                if k == 1 {
                    d.set_item(name, a)?;
                } else {
                    d.set_item(name, a.reshape([n, k])?)?;
                }
            }
            Ok::<(), PyErr>(())
        })?;
        Ok(d)
    }

    /// Simulated time (s): ``frame * frame_dt`` of the scene (not wall-clock time; the
    /// wall-clock cost of each frame is in ``stats``).
    #[getter]
    fn time(&self) -> f64 {
        each!(&*self.lock(), s => s.time_s)
    }

    /// Frames done since the scene's start (a loaded simulation counts the frames done
    /// before it was saved).
    #[getter]
    fn frame(&self) -> usize {
        each!(&*self.lock(), s => s.frame)
    }

    /// The scene's precision, "f32" or "f64": the dtype of every array (float32, float64)
    /// and of the solver's arithmetic.
    #[getter]
    fn precision(&self) -> &'static str {
        match &*self.lock() {
            AnySim::F32(_) => "f32",
            AnySim::F64(_) => "f64",
        }
    }

    /// The last frame's statistics (the frame loop's record) as a dict, or None before the
    /// first frame of this object: ``frame``, ``time_s`` (simulated), ``particles``, the
    /// density ratios, ``iterations``, ``neighbour_pairs``, ``substeps``,
    /// ``kinetic_energy_j``, ``max_speed_m_s``, ``reordered``, and the wall-clock costs
    /// ``phases_s`` (a dict by solver phase) and ``total_s`` (s).
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.record.as_ref().map(|r| record_dict(py, r)).transpose()
    }

    /// Writes the particles as a legacy VTK frame (binary, the format of ``cargo xtask
    /// run``: float32 points, velocity, density and id) to ``path``.
    fn write_vtk(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let sim = &self.sim;
        py.detach(|| {
            let guard = sim.lock().unwrap_or_else(|p| p.into_inner());
            each!(&*guard, s => s.write_vtk(&path))
        })
        .map_err(rust_err)
    }

    /// The current particles rendered with the scene's ``[render]`` settings (the image
    /// ``cargo xtask run --render`` writes), as an (H, W, 3) uint8 RGB array (H, W the
    /// ``[render]`` table's ``height``, ``width``).
    fn render<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray3<u8>>> {
        let sim = &self.sim;
        let image = py.detach(|| {
            let guard = sim.lock().unwrap_or_else(|p| p.into_inner());
            each!(&*guard, s => sph_sim::render::render_params(&s.scene)
                .and_then(|params| crate::render::render_image(&params, &s.state.positions, None)
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
