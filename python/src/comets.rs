//! `symplectic`: comet populations (Chegodaeva 2004's shared planet ephemeris), with the
//! population specification of `cargo xtask comets` and its Parquet tables.

use std::path::{Path, PathBuf};

use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use symplectic::io::{
    events_table, population_table, status_label, write_parquet, ParticleRow, PopulationSpec,
};
use symplectic::Population as RustPopulation;

use crate::arrays::{check_shape, is_f64, untyped};
use crate::rust_err;

/// States `(N, 6)` and their times `(N,)`, as returned to Python.
type StatesAndTimes<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>);

/// The planets of a population: the Sun (with the inner planets' masses) and the four
/// giants at the epoch 1994-09-05 0h, heliocentric, in `frame`.
#[pyfunction]
#[pyo3(signature = (frame = "ecliptic_j2000"))]
fn outer_solar_system_table(py: Python<'_>, frame: &str) -> PyResult<Py<PyDict>> {
    let f = match frame {
        "ecliptic_j2000" => symplectic::Frame::EclipticJ2000,
        "equatorial" => symplectic::Frame::Equatorial,
        other => {
            return Err(PyValueError::new_err(format!(
                "frame {other:?}: expected \"ecliptic_j2000\" or \"equatorial\""
            )))
        }
    };
    let planets = symplectic::outer_solar_system(f);
    let d = PyDict::new(py);
    let flat =
        |v: &[symplectic::Vec3]| -> Vec<f64> { v.iter().flat_map(|p| p.iter().copied()).collect() };
    let n = planets.len();
    let velocities = planets.heliocentric_velocities();
    d.set_item(
        "names",
        symplectic::solar_system::GIANT_PLANETS
            .map(|g| g.name)
            .to_vec(),
    )?;
    d.set_item("masses_msun", planets.masses().to_vec().into_pyarray(py))?;
    d.set_item("sun_mass_msun", planets.sun_mass())?;
    d.set_item(
        "positions_au",
        flat(planets.positions()).into_pyarray(py).reshape([n, 3])?,
    )?;
    d.set_item(
        "velocities_au_per_day",
        flat(&velocities).into_pyarray(py).reshape([n, 3])?,
    )?;
    d.set_item("g", planets.g())?;
    Ok(d.unbind())
}

/// A population of test particles (`symplectic::Population`).
#[pyclass(module = "partisim")]
struct Population {
    inner: RustPopulation,
}

/// The Python keyword of `PopulationSpec` for a field path of the specification's tables.
fn python_setting(field: &str) -> String {
    let (table, key) = field.split_once('.').unwrap_or((field, ""));
    match (table, key) {
        ("planets", "step_days") => "planet_step_days".into(),
        ("planets", "scheme") => "planet_scheme".into(),
        ("planets", "frame") => "frame".into(),
        ("removal", k) | ("encounters", k) | ("events", k) if !k.is_empty() => {
            // `removal.min_distance.distance` as `removal["min_distance"]["distance"]`.
            let keys: String = k.split('.').map(|part| format!("[{part:?}]")).collect();
            format!("{table}{keys}")
        }
        (_, "") => table.into(),
        (_, k) => k.into(),
    }
}

fn spec_from_json(spec_json: &str) -> PyResult<PopulationSpec> {
    // The specification's checks, with messages naming the Python keyword, never a line or
    // column of the JSON text the caller never wrote.
    PopulationSpec::from_json(spec_json, Path::new("PopulationSpec")).map_err(|e| match e {
        symplectic::SymplecticError::Spec { field, reason, .. } if !field.is_empty() => rust_err(
            format!("PopulationSpec {}: {reason}", python_setting(&field)),
        ),
        other => rust_err(other),
    })
}

/// Runs `work` on a thread of its own, with the GIL released, while this thread checks for
/// Ctrl-C every 50 ms: a pending signal asks the work to stop
/// ([`symplectic::guard::request_stop`]: the loops stop at their next check, leaving a state
/// that goes on) and is raised (KeyboardInterrupt) once the work has returned.
fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, symplectic::SymplecticError> + Send,
) -> PyResult<T> {
    use std::sync::mpsc::RecvTimeoutError;
    symplectic::guard::clear_stop();
    let (result, signal) = py.detach(|| {
        std::thread::scope(|scope| {
            let (tx, rx) = std::sync::mpsc::channel();
            scope.spawn(move || {
                // The receiver outlives the scope's threads.
                let _ = tx.send(work());
            });
            let mut signal = None;
            loop {
                match rx.recv_timeout(std::time::Duration::from_millis(50)) {
                    Ok(r) => return (Some(r), signal),
                    Err(RecvTimeoutError::Timeout) if signal.is_none() => {
                        if let Err(e) = Python::attach(|py| py.check_signals()) {
                            symplectic::guard::request_stop();
                            signal = Some(e);
                        }
                    }
                    Err(RecvTimeoutError::Timeout) => {}
                    // The work panicked; the scope re-raises its panic.
                    Err(RecvTimeoutError::Disconnected) => return (None, signal),
                }
            }
        })
    });
    symplectic::guard::clear_stop();
    if let Some(e) = signal {
        return Err(e);
    }
    match result {
        Some(r) => r.map_err(rust_err),
        None => Err(rust_err("the computation stopped without a result")),
    }
}

fn rows(
    particles: &Bound<'_, PyAny>,
    ids: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<ParticleRow>> {
    let a = untyped(particles, "particles")?;
    check_shape(a, "particles", "(N, 6)", Some(2), Some(6))?;
    if !is_f64(a, "particles")? {
        return Err(pyo3::exceptions::PyTypeError::new_err(
            "particles: expected a float64 array, got float32 (orbits need float64)",
        ));
    }
    let p: PyReadonlyArray2<'_, f64> = particles.extract()?;
    let p = p.as_array();
    // Counted and checked against the memory before anything is copied.
    symplectic::io::check_memory(p.nrows(), symplectic::io::available_memory())
        .map_err(rust_err)?;
    let ids: Vec<u64> = match ids {
        Some(ids) => {
            let ia = untyped(ids, "ids")?;
            check_shape(ia, "ids", "(N,)", Some(1), None)?;
            let ids: PyReadonlyArray1<'_, u64> = ids.extract().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err("ids: expected a uint64 array")
            })?;
            ids.as_array().to_vec()
        }
        None => (0..p.nrows() as u64).collect(),
    };
    if ids.len() != p.nrows() {
        return Err(PyValueError::new_err(format!(
            "ids: {} identifiers for {} particles",
            ids.len(),
            p.nrows()
        )));
    }
    let mut out = Vec::new();
    symplectic::guard::try_reserve(&mut out, p.nrows(), "the particle rows").map_err(rust_err)?;
    out.extend(
        p.rows()
            .into_iter()
            .zip(ids)
            .enumerate()
            .map(|(k, (r, id))| ParticleRow {
                line: k as u64,
                id,
                values: [r[0], r[1], r[2], r[3], r[4], r[5]],
            }),
    );
    Ok(out)
}

#[pymethods]
impl Population {
    /// Builds a population from a specification (the tables of a population TOML file,
    /// as JSON) and particle rows `(N, 6)` of the specification's `particles.kind`.
    #[staticmethod]
    #[pyo3(signature = (spec_json, particles, ids = None))]
    fn from_spec_json(
        py: Python<'_>,
        spec_json: &str,
        particles: &Bound<'_, PyAny>,
        ids: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let spec = spec_from_json(spec_json)?;
        let rows = rows(particles, ids)?;
        let inner = interruptible(py, || {
            spec.population_from_rows(&rows, Path::new("particles"))
        })?;
        Ok(Self { inner })
    }

    /// Reads a population TOML file and its particle CSV (`cargo xtask comets` input).
    #[staticmethod]
    fn from_spec_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let inner = interruptible(py, || {
            PopulationSpec::from_file(&path).and_then(|s| s.population(&path))
        })?;
        Ok(Self { inner })
    }

    /// Advances every active particle to `t_days` (days after the planets' epoch), one
    /// synchronisation window at a time; after each, `callback(progress)` (if given) sees a
    /// dict (`time_days`, `active`, `removed`, `particle_steps`) and stops the run by
    /// returning something true. Ctrl-C stops within a window (KeyboardInterrupt), each
    /// particle where it was on its own clock. Returns whether the callback stopped it.
    #[pyo3(signature = (t_days, callback = None))]
    fn advance_to_days(
        &mut self,
        py: Python<'_>,
        t_days: f64,
        callback: Option<Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        if !t_days.is_finite() {
            return Err(PyValueError::new_err(format!(
                "to_years = {}: must be finite",
                t_days / symplectic::io::DAYS_PER_YEAR
            )));
        }
        let window = f64::from(self.inner.window_steps()) * self.inner.ephemeris().grid_step();
        loop {
            // The same windows advance_to cuts, one call each: a particle's trajectory does
            // not depend on where the calls stop (Population's determinism).
            let end = (self.inner.time() + window).min(t_days);
            let inner = &mut self.inner;
            let p = interruptible(py, || inner.advance_to(end, |_| {}))?;
            if let Some(cb) = &callback {
                let d = PyDict::new(py);
                d.set_item("time_days", self.inner.time())?;
                d.set_item("active", p.active)?;
                d.set_item("removed", p.removed)?;
                d.set_item("particle_steps", p.particle_steps)?;
                if cb.call1((d,))?.is_truthy()? {
                    return Ok(true);
                }
            }
            if end >= t_days {
                return Ok(false);
            }
        }
    }

    /// The population's time (days after the planets' epoch).
    #[getter]
    fn time_days(&self) -> f64 {
        self.inner.time()
    }

    /// Particle steps done in total.
    #[getter]
    fn particle_steps(&self) -> u64 {
        self.inner.progress().particle_steps
    }

    /// Number of particles (active and removed).
    fn __len__(&self) -> usize {
        self.inner.members().len()
    }

    /// Each particle's status label (`active`, `hill_sphere_<planet name>`,
    /// `collision_<planet name>`, `perihelion`, `ejected`, `regularisation_lost`, `failed`),
    /// in identifier order.
    #[getter]
    fn status(&self) -> Vec<String> {
        let planets = self.inner.ephemeris().planets();
        self.inner
            .members()
            .iter()
            .map(|m| status_label(&m.status, planets).0)
            .collect()
    }

    /// The snapshot table (the columns of `cargo xtask comets`' Parquet snapshots) as a
    /// dict of numpy arrays (`status`, `region` and `levison_class` lists of str,
    /// `in_encounter` booleans; `encounters_begun`, `planet_encounters`,
    /// `planet_encounter_switches` and `max_switches_per_encounter` integers: the switches to
    /// the encounter mode, the close encounters with the planets, the switches in them and the
    /// most in one, `symplectic::EncounterTally`).
    fn table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let batch = population_table(&self.inner).map_err(rust_err)?;
        batch_dict(py, &batch)
    }

    /// The events table (`symplectic::io::events_table`, the study's `events.parquet`) as a
    /// dict of numpy arrays (`event` and `planet` lists of str, `ongoing` booleans).
    fn events_table<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let batch = events_table(&self.inner).map_err(rust_err)?;
        batch_dict(py, &batch)
    }

    /// Writes the events table as Parquet, atomically.
    fn write_events_parquet(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inner = &self.inner;
        py.detach(|| events_table(inner).and_then(|b| write_parquet(&path, &b)))
            .map_err(rust_err)
    }

    /// Writes the snapshot table as Parquet (readable by pandas and polars), atomically.
    fn write_parquet(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inner = &self.inner;
        py.detach(|| population_table(inner).and_then(|b| write_parquet(&path, &b)))
            .map_err(rust_err)
    }

    /// The members `start..stop` as a population of their own (`Population::shard`).
    fn shard(&self, start: usize, stop: usize) -> PyResult<Self> {
        if start > stop {
            return Err(PyValueError::new_err(format!(
                "shard {start}..{stop}: start after stop"
            )));
        }
        Ok(Self {
            inner: self.inner.shard(start..stop).map_err(rust_err)?,
        })
    }

    /// Joins shards of one population advanced to the same time (`Population::merge`).
    #[staticmethod]
    fn merge(py: Python<'_>, shards: Vec<PyRef<'_, Population>>) -> PyResult<Self> {
        let shards: Vec<RustPopulation> = shards.iter().map(|s| s.inner.clone()).collect();
        let inner = interruptible(py, || RustPopulation::merge(shards))?;
        Ok(Self { inner })
    }

    /// Writes the whole population atomically (the Rust checkpoint format).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inner = &self.inner;
        py.detach(|| inner.save(&path)).map_err(rust_err)
    }

    /// Reads a population written by `save`.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let inner = interruptible(py, || RustPopulation::load(&path))?;
        Ok(Self { inner })
    }

    /// The whole population as bytes (JSON of the Rust state, float round trip exact), for
    /// pickling across processes.
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let v = serde_json::to_vec(&self.inner).map_err(rust_err)?;
        Ok(PyBytes::new(py, &v))
    }

    /// A population from `to_bytes`.
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<Self> {
        let inner = serde_json::from_slice(data)
            .map_err(|e| rust_err(format!("not a population's bytes: {e}")))?;
        Ok(Self { inner })
    }

    /// Barycentric states `(N, 6)`: x, y, z (AU), vx, vy, vz (AU/day), in identifier order.
    #[getter]
    fn states<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (flat, _) = self.states_at(None)?;
        flat.into_pyarray(py)
            .reshape([self.inner.members().len(), 6])
    }

    /// Barycentric osculating elements (`μ = G M`) of every particle, as a dict of `(N,)`
    /// arrays: `a_au`, `e`, `i_deg`, `node_deg`, `peri_deg`, `mean_anomaly_deg`, `q_au`, and
    /// `time_days`, the time they hold at. Each particle at its own time, or with `at_days`
    /// every active one carried to `at_days` along its osculating two-body orbit (a Kepler
    /// drift about `G M`; removed particles stay at their own time).
    #[pyo3(signature = (at_days = None))]
    fn elements<'py>(&self, py: Python<'py>, at_days: Option<f64>) -> PyResult<Bound<'py, PyDict>> {
        let (flat, times) = self.states_at(at_days)?;
        let mu = self.inner.total_gm();
        let names = [
            "a_au",
            "e",
            "i_deg",
            "node_deg",
            "peri_deg",
            "mean_anomaly_deg",
            "q_au",
        ];
        let mut cols: Vec<Vec<f64>> = names
            .iter()
            .map(|_| Vec::with_capacity(times.len()))
            .collect();
        for s in flat.chunks_exact(6) {
            let r = symplectic::Vec3::new(s[0], s[1], s[2]);
            let v = symplectic::Vec3::new(s[3], s[4], s[5]);
            let row = match symplectic::io::conic_elements(&r, &v, mu) {
                Ok(el) => [
                    el.perihelion / (1.0 - el.eccentricity),
                    el.eccentricity,
                    el.inclination.to_degrees(),
                    el.node.to_degrees(),
                    el.argument_of_perihelion.to_degrees(),
                    el.mean_anomaly.to_degrees(),
                    el.perihelion,
                ],
                Err(_) => [f64::NAN; 7],
            };
            for (c, x) in cols.iter_mut().zip(row) {
                c.push(x);
            }
        }
        let d = PyDict::new(py);
        for (name, c) in names.iter().zip(cols) {
            d.set_item(name, c.into_pyarray(py))?;
        }
        d.set_item("time_days", times.into_pyarray(py))?;
        Ok(d)
    }

    /// Barycentric states `(N, 6)` at `at_days` (see `elements`), flat, and their times.
    #[pyo3(signature = (at_days = None))]
    fn states_at_days<'py>(
        &self,
        py: Python<'py>,
        at_days: Option<f64>,
    ) -> PyResult<StatesAndTimes<'py>> {
        let (flat, times) = self.states_at(at_days)?;
        let n = times.len();
        Ok((
            flat.into_pyarray(py).reshape([n, 6])?,
            times.into_pyarray(py),
        ))
    }

    /// Identifiers, in member order.
    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        let ids: Vec<u64> = self.inner.members().iter().map(|m| m.id).collect();
        ids.into_pyarray(py)
    }
}

impl Population {
    /// Every member's barycentric state, flat `(N·6)`, and its time: its own, or `at_days`
    /// for an active member carried there by a Kepler drift about `G M`.
    fn states_at(&self, at_days: Option<f64>) -> PyResult<(Vec<f64>, Vec<f64>)> {
        if let Some(t) = at_days {
            if !t.is_finite() {
                return Err(PyValueError::new_err(format!(
                    "at_time {t}: must be finite"
                )));
            }
        }
        let m = self.inner.members();
        let mu = self.inner.total_gm();
        let mut flat = Vec::new();
        symplectic::guard::try_reserve(&mut flat, 6 * m.len(), "the states").map_err(rust_err)?;
        let mut times = Vec::with_capacity(m.len());
        for (i, member) in m.iter().enumerate() {
            let mut q = self.inner.barycentric_position(i);
            let mut v = member.particle.velocity;
            let mut t = member.particle.time;
            if let Some(at) =
                at_days.filter(|_| member.status == symplectic::ParticleStatus::Active)
            {
                symplectic::kepler::drift(&mut q, &mut v, mu, at - t).map_err(rust_err)?;
                t = at;
            }
            flat.extend_from_slice(&[q.x, q.y, q.z, v.x, v.y, v.z]);
            times.push(t);
        }
        Ok((flat, times))
    }
}

/// The columns of `batch` as a dict: numpy arrays of `f64`, `u64` and `bool`, lists of str.
fn batch_dict<'py>(
    py: Python<'py>,
    batch: &arrow_array::RecordBatch,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let schema = batch.schema();
    for (field, col) in schema.fields().iter().zip(batch.columns()) {
        let any = col.as_any();
        if let Some(a) = any.downcast_ref::<arrow_array::Float64Array>() {
            d.set_item(field.name(), a.values().to_vec().into_pyarray(py))?;
        } else if let Some(a) = any.downcast_ref::<arrow_array::UInt64Array>() {
            d.set_item(field.name(), a.values().to_vec().into_pyarray(py))?;
        } else if let Some(a) = any.downcast_ref::<arrow_array::StringArray>() {
            let v: Vec<&str> = a.iter().map(|s| s.unwrap_or("")).collect();
            d.set_item(field.name(), v)?;
        } else if let Some(a) = any.downcast_ref::<arrow_array::BooleanArray>() {
            let v: Vec<bool> = a.iter().map(|b| b.unwrap_or(false)).collect();
            d.set_item(field.name(), v.into_pyarray(py))?;
        }
    }
    Ok(d)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Population>()?;
    m.add_function(wrap_pyfunction!(outer_solar_system_table, m)?)
}
