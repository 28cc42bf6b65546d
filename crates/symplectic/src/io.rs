//! Population files (feature `io`): the population specification (TOML), the particle file
//! (CSV) and (feature `parquet`) the output tables (Apache Parquet), reusable from any front
//! end (the `particles comets` command, the Python package).
//!
//! Units: AU, days, degrees for angles in files, years for spans in the specification.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::kepler::{state_from_elements, ConicElements};
use crate::{
    outer_solar_system, DistanceFrame, Ephemeris, EventRules, Frame, Integrator,
    ParticleIntegrator, ParticleStatus, Planets, Population, RemovalRules, Scheme, SymplecticError,
    Variant, Vec3,
};

#[cfg(feature = "parquet")]
mod events_table;
#[cfg(feature = "parquet")]
mod tables;
#[cfg(feature = "parquet")]
pub use events_table::{events_table, EVENTS_TABLE};
#[cfg(feature = "parquet")]
pub use tables::{population_table, write_parquet};

/// Days per Julian year, the unit of spans in the specification.
pub const DAYS_PER_YEAR: f64 = 365.25;

/// Largest population specification read (bytes): a specification is a few tables of
/// settings, a few hundred bytes; anything near this size is not one.
pub const MAX_SPEC_FILE_BYTES: u64 = 1 << 20;

/// Largest particle file read (bytes, 64 GiB): about 10⁹ rows of seven numbers. Below it,
/// the rows are counted and checked against the memory available before any is kept.
pub const MAX_PARTICLE_FILE_BYTES: u64 = 1 << 36;

/// Most snapshot tables one study writes: `⌈span.years / span.snapshot_every_years⌉ + 1`
/// (the first at the epoch, the last at the end; [`snapshot_count`]). A cadence far below
/// the span writes files faster than anyone reads them.
pub const MAX_SNAPSHOTS: f64 = 10_000.0;

/// The number of snapshot tables a study of `span_years` with one every `every_years`
/// writes: at the epoch, every `every_years` after it, and at the end,
/// `⌈span/every⌉ + 1` (as a float: a cadence far below the span asks for more than any
/// integer type holds).
pub fn snapshot_count(span_years: f64, every_years: f64) -> f64 {
    (span_years / every_years).ceil() + 1.0
}

/// Most checkpoints one study writes (`span.years / span.checkpoint_every_years`): each
/// rewrites the whole population.
pub const MAX_CHECKPOINTS: f64 = 100_000.0;

/// Largest planets' grid one particle step may need (bytes, 1 GiB): the grid must cover a
/// particle's whole step plus two synchronisation windows, `(first step + 2 windows) /
/// planet step` states of 360 bytes (positions, velocities and accelerations of the Sun and
/// four planets). A planet step of a few seconds against particle steps of a year and a
/// half asks for more; the giant planets' shortest period, Jupiter's 4333 days, needs
/// nothing like it.
pub const MAX_STEP_GRID_BYTES: f64 = (1u64 << 30) as f64;

/// A population study as written in a TOML file (every table and field is checked; an
/// unknown field is an error naming it).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PopulationSpec {
    /// The planets and their integrator.
    pub planets: PlanetsSpec,
    /// The particles' integrator.
    pub integrator: IntegratorSpec,
    /// The particle file.
    pub particles: ParticlesSpec,
    /// How long, how often to write.
    pub span: SpanSpec,
    /// When particles are removed (all rules off if the table is absent).
    #[serde(default)]
    pub removal: RemovalRules,
    /// Integration through close encounters ([`Encounters`](crate::Encounters); off if the
    /// table is absent; `[encounters]` with no field takes the defaults: switch at 3 Hill
    /// radii, hand back beyond 3.5, tolerance 10⁻¹²).
    #[serde(default)]
    pub encounters: Option<crate::Encounters>,
    /// What is recorded without removing ([`EventRules`]; none if the table is absent):
    /// `perihelion_below = [2.5]`, `tisserand_crossing = true`,
    /// `close_approach = { hill_radii = 1.0 }` (or `{ au = 0.1 }`), `max_per_particle`.
    #[serde(default)]
    pub events: EventRules,
}

/// The planetary system.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlanetSystem {
    /// The Sun (with the inner planets' masses) and the four giant planets of
    /// [`outer_solar_system`], epoch 1994-09-05 0h at `t = 0`.
    OuterSolarSystem,
}

/// A reference frame of the planet table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameSpec {
    /// [`Frame::EclipticJ2000`].
    EclipticJ2000,
    /// [`Frame::Equatorial`].
    Equatorial,
}

/// A composition of the planets' or the particles' map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SchemeSpec {
    /// Second order.
    S2,
    /// Pseudo-sixth order (Laskar & Robutel).
    S6,
}

/// `[planets]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanetsSpec {
    /// Which planets.
    pub system: PlanetSystem,
    /// Frame of positions and velocities (particles are read in the same frame).
    pub frame: FrameSpec,
    /// The planets' map.
    pub scheme: SchemeSpec,
    /// The planets' fixed step (days), the ephemeris grid spacing.
    pub step_days: f64,
}

/// `[integrator]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegratorSpec {
    /// `"barycentric"` or `"mixed"`.
    pub variant: VariantSpec,
    /// `"s2"` or `"s6"`.
    pub scheme: SchemeSpec,
    /// `B₀` (AU²/day²).
    #[serde(default)]
    pub b0: f64,
    /// `B₁` (AU³/day²).
    pub b1: f64,
    /// First physical step of every particle (days).
    pub initial_step_days: f64,
    /// Planet steps per synchronisation window (default
    /// [`DEFAULT_WINDOW_STEPS`](crate::DEFAULT_WINDOW_STEPS)).
    pub window_steps: Option<u32>,
}

/// Coordinates of the particle map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VariantSpec {
    /// [`Variant::Barycentric`].
    Barycentric,
    /// [`Variant::Mixed`].
    Mixed,
}

/// What the particle file's rows are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParticleKind {
    /// Columns `id,x,y,z,vx,vy,vz` (AU, AU/day), barycentric.
    BarycentricState,
    /// Columns `id,x,y,z,vx,vy,vz`, heliocentric (velocity relative to the Sun).
    HeliocentricState,
    /// Columns `id,a,e,i,node,peri,mean_anomaly` (AU, degrees): barycentric osculating
    /// elements about `G M` (the total mass); `a < 0` with `e > 1` for a hyperbola.
    BarycentricElements,
    /// The same columns, heliocentric osculating elements about `G m₀`.
    HeliocentricElements,
}

/// `[particles]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticlesSpec {
    /// CSV file, relative to the specification's directory.
    pub file: PathBuf,
    /// What its rows are.
    pub kind: ParticleKind,
    /// Epoch of the rows (days after the planets' epoch, `>= 0`).
    #[serde(default)]
    pub epoch_days: f64,
}

/// `[span]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpanSpec {
    /// Integration span after the epoch (years).
    pub years: f64,
    /// Snapshot cadence (years).
    pub snapshot_every_years: f64,
    /// Checkpoint cadence (years, from the epoch; default: at every snapshot). A study also
    /// writes its checkpoint at the end and when stopped by Ctrl-C, never at the snapshots
    /// between two checkpoint times.
    pub checkpoint_every_years: Option<f64>,
}

impl PopulationSpec {
    /// Reads and checks a specification; errors name the file, the field and, for syntax,
    /// the line and column. Only a regular file of at most [`MAX_SPEC_FILE_BYTES`] is read
    /// (a named pipe or a device is refused before it is opened).
    pub fn from_file(path: &Path) -> Result<Self, SymplecticError> {
        Self::parse(&read_spec_text(path)?, path)
    }

    /// Checks a specification given as a JSON document of the same tables (a front end's
    /// settings rather than a file; `origin` names it in messages). Errors name the field by
    /// its path in the tables (`planets.step_days`), never a line or column of the JSON text.
    pub fn from_json(text: &str, origin: &Path) -> Result<Self, SymplecticError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| spec_error(origin, "", e.to_string()))?;
        let spec: Self = serde_path_to_error::deserialize(value).map_err(|e| {
            let field = e.path().to_string();
            spec_error(origin, &field, e.inner().to_string().trim().to_string())
        })?;
        spec.check(origin)?;
        Ok(spec)
    }

    /// Parses and checks specification text; `path` names it in messages.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SymplecticError> {
        let de = toml::de::Deserializer::parse(text)
            .map_err(|e| spec_error(path, "", e.to_string().trim().to_string()))?;
        let spec: Self = serde_path_to_error::deserialize(de).map_err(|e| {
            let field = e.path().to_string();
            spec_error(path, &field, e.inner().to_string().trim().to_string())
        })?;
        spec.check(path)?;
        Ok(spec)
    }

    fn check(&self, path: &Path) -> Result<(), SymplecticError> {
        let positive = [
            ("planets.step_days", self.planets.step_days),
            (
                "integrator.initial_step_days",
                self.integrator.initial_step_days,
            ),
            ("span.years", self.span.years),
            ("span.snapshot_every_years", self.span.snapshot_every_years),
        ];
        for (field, v) in positive.into_iter().chain(
            self.span
                .checkpoint_every_years
                .map(|v| ("span.checkpoint_every_years", v)),
        ) {
            if !(v.is_finite() && v > 0.0) {
                return Err(spec_error(
                    path,
                    field,
                    format!("{v} must be finite and > 0"),
                ));
            }
        }
        if !(self.particles.epoch_days.is_finite() && self.particles.epoch_days >= 0.0) {
            return Err(spec_error(
                path,
                "particles.epoch_days",
                format!(
                    "{} is outside the ephemeris (it starts at the planets' epoch, 0, and runs forward)",
                    self.particles.epoch_days
                ),
            ));
        }
        if self.integrator.window_steps == Some(0) {
            return Err(spec_error(
                path,
                "integrator.window_steps",
                "must be >= 1".into(),
            ));
        }
        // The rules' own checks, with the file and the table named.
        let named = |table: &str, e: SymplecticError| match e {
            SymplecticError::InvalidParameter {
                name,
                value,
                reason,
            } => spec_error(
                path,
                &format!("{table}{name}"),
                format!("{value}: {reason}"),
            ),
            other => other,
        };
        self.removal.validate().map_err(|e| named("removal.", e))?;
        self.events.validate().map_err(|e| named("", e))?;
        self.check_limits(path)
    }

    /// The limits that keep a run finite: the snapshot and checkpoint counts, the planets'
    /// grid one particle step needs, a first step that moves the particles' clocks.
    fn check_limits(&self, path: &Path) -> Result<(), SymplecticError> {
        let span = &self.span;
        let snapshots = snapshot_count(span.years, span.snapshot_every_years);
        if snapshots > MAX_SNAPSHOTS {
            // The count exactly while f64 holds it as an integer (2⁵³), in e-notation beyond.
            let requested = if snapshots < 2f64.powi(53) {
                format!("{snapshots:.0}")
            } else {
                format!("{snapshots:.3e}")
            };
            return Err(spec_error(
                path,
                "span.snapshot_every_years",
                format!(
                    "one snapshot every {} years over a span of {} years is {requested} snapshot files (at the epoch, every {} years, at the end), more than the cap of {MAX_SNAPSHOTS} per study (MAX_SNAPSHOTS): take at least {:.6e} years",
                    span.snapshot_every_years,
                    span.years,
                    span.snapshot_every_years,
                    span.years / (MAX_SNAPSHOTS - 1.0)
                ),
            ));
        }
        if let Some(every) = span.checkpoint_every_years {
            let checkpoints = span.years / every;
            if checkpoints > MAX_CHECKPOINTS {
                return Err(spec_error(
                    path,
                    "span.checkpoint_every_years",
                    format!(
                        "{every} years over a span of {} years writes {checkpoints:.3e} checkpoints, more than MAX_CHECKPOINTS = {MAX_CHECKPOINTS}: take at least {:.6e} years",
                        span.years,
                        span.years / MAX_CHECKPOINTS
                    ),
                ));
            }
        }
        let planet_step = self.planets.step_days;
        let first_step = self.integrator.initial_step_days;
        let window_steps = f64::from(
            self.integrator
                .window_steps
                .unwrap_or(crate::DEFAULT_WINDOW_STEPS),
        );
        let grid_bytes = (first_step / planet_step + 2.0 * window_steps + 1.0) * GRID_STATE_BYTES;
        let window_bytes = (2.0 * window_steps + 1.0) * GRID_STATE_BYTES;
        if window_bytes > MAX_STEP_GRID_BYTES {
            return Err(spec_error(
                path,
                "integrator.window_steps",
                format!(
                    "{window_steps} planet steps per window: the planets' grid of two windows would take {window_bytes:.3e} bytes, more than MAX_STEP_GRID_BYTES = {MAX_STEP_GRID_BYTES:.3e}; take at most {:.0}",
                    (MAX_STEP_GRID_BYTES / GRID_STATE_BYTES - 1.0) / 2.0 - 1.0
                ),
            ));
        }
        if grid_bytes > MAX_STEP_GRID_BYTES {
            let shortest =
                first_step / (MAX_STEP_GRID_BYTES / GRID_STATE_BYTES - 2.0 * window_steps - 1.0);
            return Err(spec_error(
                path,
                "planets.step_days",
                format!(
                    "{planet_step} days is too short for particle steps of {first_step} days: the planets' grid of one particle step would take {grid_bytes:.3e} bytes, more than MAX_STEP_GRID_BYTES = {MAX_STEP_GRID_BYTES:.3e}; take at least {shortest:.3e} days"
                ),
            ));
        }
        // The first synchronisation, or the span's end if later: a step that does not change
        // a time of that size in f64 never gets the particles there.
        let reach = self.particles.epoch_days
            + (window_steps * planet_step).max(span.years * DAYS_PER_YEAR);
        if reach + first_step <= reach {
            return Err(spec_error(
                path,
                "integrator.initial_step_days",
                format!(
                    "{first_step} days makes no progress in f64 at t = {reach:.6e} days, which the particles must reach: take at least {:.3e} days",
                    2.0 * reach * f64::EPSILON
                ),
            ));
        }
        Ok(())
    }

    /// The planets' ephemeris.
    pub fn ephemeris(&self) -> Result<Ephemeris, SymplecticError> {
        let frame = match self.planets.frame {
            FrameSpec::EclipticJ2000 => Frame::EclipticJ2000,
            FrameSpec::Equatorial => Frame::Equatorial,
        };
        let planets = match self.planets.system {
            PlanetSystem::OuterSolarSystem => outer_solar_system(frame),
        };
        let step = self.planets.step_days;
        let integrator = match self.planets.scheme {
            SchemeSpec::S2 => Integrator::S2 { step },
            SchemeSpec::S6 => Integrator::S6 { step },
        };
        Ephemeris::new(planets, integrator)
    }

    /// The particles' integrator.
    pub fn particle_integrator(&self) -> Result<ParticleIntegrator, SymplecticError> {
        let variant = match self.integrator.variant {
            VariantSpec::Barycentric => Variant::Barycentric,
            VariantSpec::Mixed => Variant::Mixed,
        };
        let scheme = match self.integrator.scheme {
            SchemeSpec::S2 => Scheme::S2,
            SchemeSpec::S6 => Scheme::S6,
        };
        ParticleIntegrator::new(variant, scheme, self.integrator.b0, self.integrator.b1)
    }

    /// The particle file's path (relative paths from the specification's directory).
    pub fn particle_file(&self, spec_path: &Path) -> PathBuf {
        spec_path
            .parent()
            .unwrap_or(Path::new(""))
            .join(&self.particles.file)
    }

    /// Reads the particle file and builds the population at the epoch (nothing is written).
    pub fn population(&self, spec_path: &Path) -> Result<Population, SymplecticError> {
        let file = self.particle_file(spec_path);
        let rows = read_particle_rows(&file, self.particles.kind)?;
        self.population_from_rows(&rows, &file)
    }

    /// Builds the population at the epoch from rows given directly (a front end's array
    /// rather than the particle file; `origin` names them in messages, `line` the row).
    /// Each row is checked as the file's are: finite values, a state off the origin,
    /// elements whose `a` and `e` agree; identifiers must be distinct.
    pub fn population_from_rows(
        &self,
        rows: &[ParticleRow],
        origin: &Path,
    ) -> Result<Population, SymplecticError> {
        let mut ephemeris = self.ephemeris()?;
        let integrator = self.particle_integrator()?;
        check_memory(rows.len(), available_memory())?;
        let kind = self.particles.kind;
        for (k, row) in rows.iter().enumerate() {
            if k.is_multiple_of(65536) {
                crate::guard::check_stop("checking the particle rows")?;
            }
            let names = particle_columns(kind);
            if let Some(c) = row.values.iter().position(|v| !v.is_finite()) {
                let reason = format!("{} is not a finite number", row.values[c]);
                return Err(particle_error(origin, row.line, names[c], reason));
            }
            check_row(&row.values, kind)
                .map_err(|(name, reason)| particle_error(origin, row.line, name, reason))?;
        }
        let epoch = self.particles.epoch_days;
        let mut bodies = crate::BodyStates::default();
        ephemeris.bodies_at(epoch, &mut bodies)?;
        let mut states = Vec::new();
        crate::guard::try_reserve(&mut states, rows.len(), "the particles' initial states")?;
        for row in rows {
            states.push(
                to_integrator_state(row, kind, integrator.variant, &bodies)
                    .map_err(|reason| particle_error(origin, row.line, "", reason))?,
            );
        }
        let mut ids = Vec::new();
        crate::guard::try_reserve(&mut ids, rows.len(), "the particles' identifiers")?;
        ids.extend(rows.iter().map(|r| r.id));
        let mut population = Population::new(
            ephemeris,
            integrator,
            self.removal,
            epoch,
            self.integrator.initial_step_days,
            &states,
            &ids,
        )?;
        if let Some(w) = self.integrator.window_steps {
            population.set_window_steps(w)?;
        }
        population.set_encounters(self.encounters)?;
        population.set_events(self.events.clone())?;
        Ok(population)
    }
}

/// Bytes of one state of the planets' grid: positions, velocities and accelerations of the
/// Sun and the four giant planets.
const GRID_STATE_BYTES: f64 = (9 * 5 * 8) as f64;

/// The text of a specification file, guarded ([`MAX_SPEC_FILE_BYTES`], regular files only).
pub fn read_spec_text(path: &Path) -> Result<String, SymplecticError> {
    crate::guard::read_text_limited(path, MAX_SPEC_FILE_BYTES, "MAX_SPEC_FILE_BYTES")
        .map_err(|reason| spec_error(path, "", reason))
}

fn spec_error(path: &Path, field: &str, reason: String) -> SymplecticError {
    SymplecticError::Spec {
        path: path.display().to_string(),
        field: field.to_string(),
        reason,
    }
}

fn particle_error(path: &Path, line: u64, column: &str, reason: String) -> SymplecticError {
    SymplecticError::ParticleFile {
        path: path.display().to_string(),
        line,
        column: column.to_string(),
        reason,
    }
}

/// One row of a particle file: the identifier and six numbers in the kind's column order.
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleRow {
    /// Line in the file (1-based, the header is line 1).
    pub line: u64,
    /// Identifier.
    pub id: u64,
    /// `x,y,z,vx,vy,vz` or `a,e,i,node,peri,mean_anomaly`.
    pub values: [f64; 6],
}

/// Column names of a particle file of `kind`, after `id`.
pub fn particle_columns(kind: ParticleKind) -> [&'static str; 6] {
    match kind {
        ParticleKind::BarycentricState | ParticleKind::HeliocentricState => {
            ["x", "y", "z", "vx", "vy", "vz"]
        }
        ParticleKind::BarycentricElements | ParticleKind::HeliocentricElements => {
            ["a", "e", "i", "node", "peri", "mean_anomaly"]
        }
    }
}

/// Reads a particle CSV: a header naming `id` and the kind's six columns (any order, no
/// others), then one particle per row. Errors name the line and column: a missing column, a
/// value that is not a finite number, a state at the origin, elements out of range or whose
/// sign of `a` contradicts `e` (bound/unbound mismatch), a repeated identifier.
pub fn read_particle_rows(
    path: &Path,
    kind: ParticleKind,
) -> Result<Vec<ParticleRow>, SymplecticError> {
    // Only a regular file (a named pipe would block in `open`, a device never ends); its
    // lines are counted and checked against the memory available before any row is kept.
    crate::guard::regular_file_size(path, MAX_PARTICLE_FILE_BYTES, "MAX_PARTICLE_FILE_BYTES")
        .map_err(|reason| particle_error(path, 0, "", reason))?;
    let lines = count_lines(path)?;
    check_memory(lines, available_memory())?;
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| particle_error(path, 0, "", e.to_string()))?;
    let header = reader
        .headers()
        .map_err(|e| particle_error(path, 1, "", e.to_string()))?
        .clone();
    let names = particle_columns(kind);
    let index_of = |name: &str| header.iter().position(|h| h == name);
    let id_col =
        index_of("id").ok_or_else(|| particle_error(path, 1, "id", "missing column".into()))?;
    let mut cols = [0usize; 6];
    for (c, name) in cols.iter_mut().zip(names) {
        *c = index_of(name).ok_or_else(|| {
            particle_error(
                path,
                1,
                name,
                format!(
                    "missing column (a {kind:?} file has id,{})",
                    names.join(",")
                ),
            )
        })?;
    }
    if let Some(extra) = header.iter().find(|h| *h != "id" && !names.contains(h)) {
        return Err(particle_error(
            path,
            1,
            extra,
            format!(
                "unknown column (a {kind:?} file has id,{})",
                names.join(",")
            ),
        ));
    }
    let mut rows = Vec::new();
    crate::guard::try_reserve(&mut rows, lines, "the particle file's rows")?;
    let mut seen = std::collections::HashSet::new();
    seen.try_reserve(lines)
        .map_err(|_| SymplecticError::AllocationFailed {
            what: "the particle file's identifiers",
            requested_bytes: lines as u128 * 16,
            available_bytes: available_memory(),
        })?;
    for (k, record) in reader.records().enumerate() {
        if k.is_multiple_of(65536) {
            crate::guard::check_stop("reading the particle file")?;
        }
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            particle_error(path, line, "", e.to_string())
        })?;
        let line = record.position().map_or(0, |p| p.line());
        let field = |c: usize, name: &str| {
            record
                .get(c)
                .ok_or_else(|| particle_error(path, line, name, "missing value".into()))
        };
        let id_text = field(id_col, "id")?;
        let id: u64 = id_text.parse().map_err(|_| {
            particle_error(
                path,
                line,
                "id",
                format!("{id_text:?} is not a non-negative integer"),
            )
        })?;
        if !seen.insert(id) {
            return Err(particle_error(
                path,
                line,
                "id",
                format!("identifier {id} appears twice"),
            ));
        }
        let mut values = [0.0; 6];
        for ((v, &c), name) in values.iter_mut().zip(&cols).zip(names) {
            let text = field(c, name)?;
            *v = text
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    particle_error(path, line, name, format!("{text:?} is not a finite number"))
                })?;
        }
        check_row(&values, kind)
            .map_err(|(name, reason)| particle_error(path, line, name, reason))?;
        rows.push(ParticleRow { line, id, values });
    }
    Ok(rows)
}

/// Lines of the file at `path` (an upper bound of its rows), read in blocks with Ctrl-C
/// checked.
fn count_lines(path: &Path) -> Result<usize, SymplecticError> {
    use std::io::Read;
    let err = |e: std::io::Error| particle_error(path, 0, "", e.to_string());
    let mut file = std::fs::File::open(path).map_err(err)?;
    let mut block = vec![0u8; 1 << 20];
    let mut lines = 1usize;
    loop {
        crate::guard::check_stop("counting the particle file's rows")?;
        let n = file.read(&mut block).map_err(err)?;
        if n == 0 {
            return Ok(lines);
        }
        lines += block[..n].iter().filter(|&&b| b == b'\n').count();
    }
}

fn check_row(v: &[f64; 6], kind: ParticleKind) -> Result<(), (&'static str, String)> {
    match kind {
        ParticleKind::BarycentricState | ParticleKind::HeliocentricState => {
            let r = Vec3::new(v[0], v[1], v[2]).norm();
            if r <= 0.0 {
                return Err(("x", format!("distance {r} must be > 0")));
            }
        }
        ParticleKind::BarycentricElements | ParticleKind::HeliocentricElements => {
            let (a, e) = (v[0], v[1]);
            if e < 0.0 {
                return Err(("e", format!("eccentricity {e} must be >= 0")));
            }
            if e == 1.0 || a == 0.0 {
                return Err(("a", format!("a = {a}, e = {e}: a parabola has no semi-major axis; give a hyperbola (a < 0, e > 1) or an ellipse")));
            }
            if (a > 0.0) != (e < 1.0) {
                return Err((
                    "a",
                    format!(
                        "a = {a} with e = {e}: {} (bound orbits have a > 0 and e < 1, unbound a < 0 and e > 1)",
                        if a > 0.0 { "a bound a with an unbound e" } else { "an unbound a with a bound e" }
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The state in the integrator's coordinates (barycentric or heliocentric position,
/// barycentric velocity) of a row, with the bodies at the epoch.
fn to_integrator_state(
    row: &ParticleRow,
    kind: ParticleKind,
    variant: Variant,
    bodies: &crate::BodyStates,
) -> Result<(Vec3, Vec3), String> {
    let v = &row.values;
    let (sun_q, sun_v) = (bodies.positions[0], bodies.velocities[0]);
    let deg = std::f64::consts::PI / 180.0;
    let elements = || ConicElements {
        perihelion: v[0] * (1.0 - v[1]),
        eccentricity: v[1],
        inclination: v[2] * deg,
        node: v[3] * deg,
        argument_of_perihelion: v[4] * deg,
        mean_anomaly: v[5] * deg,
    };
    // Barycentric position and velocity.
    let (q, w) = match kind {
        ParticleKind::BarycentricState => {
            (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]))
        }
        ParticleKind::HeliocentricState => (
            Vec3::new(v[0], v[1], v[2]) + sun_q,
            Vec3::new(v[3], v[4], v[5]) + sun_v,
        ),
        ParticleKind::BarycentricElements => {
            state_from_elements(&elements(), bodies.total_gm()).map_err(|e| e.to_string())?
        }
        ParticleKind::HeliocentricElements => {
            let (q, w) =
                state_from_elements(&elements(), bodies.gm[0]).map_err(|e| e.to_string())?;
            (q + sun_q, w + sun_v)
        }
    };
    Ok(match variant {
        Variant::Barycentric => (q, w),
        Variant::Mixed => (q - sun_q, w),
    })
}

/// The six classical elements of the state `(r, v)` about a centre of gravitational
/// parameter `mu`, the inverse of [`state_from_elements`] (angles in radians, in `[0, 2π)`):
/// `h = r × v`, the eccentricity vector `e = v × h/μ − r/|r|`, the node vector `n = ẑ × h`;
/// `i = acos(h_z/|h|)`, `Ω = atan2(n_y, n_x)`, `ω` the angle from `n` to `e` and the true
/// anomaly `ν` from `e` to `r` in the orbital plane; `M = E − e sin E` with
/// `E = atan2(√(1−e²) sin ν, e + cos ν)`, or `M = e sinh H − H` with
/// `sinh H = √(e²−1) sin ν/(1 + e cos ν)` for a hyperbola; `q = |h|²/(μ(1 + e))`.
/// Conventions where an angle is undefined: `Ω = 0` for `i = 0` (then `ω` is measured from
/// `x̂`), `ω = 0` for `e = 0` (then `ν` is measured from the node line).
pub fn conic_elements(r: &Vec3, v: &Vec3, mu: f64) -> Result<ConicElements, SymplecticError> {
    // Checks the state and gives q, e, i.
    let shape = crate::kepler::elements(r, v, mu)?;
    let h = r.cross(v);
    if h.norm() == 0.0 {
        return Err(SymplecticError::InvalidState {
            what: "osculating elements",
            reason: format!("r = {r:?}, v = {v:?}: a radial orbit has no orbital plane"),
        });
    }
    let tau = std::f64::consts::TAU;
    let w = h.normalize();
    let e_vec = v.cross(&h) / mu - r / r.norm();
    let e = shape.eccentricity;
    let n = Vec3::new(-h.y, h.x, 0.0);
    let node_dir = if n.norm() > 0.0 {
        n.normalize()
    } else {
        Vec3::x()
    };
    // Angles in the orbital plane, from `from` to `to`, about `w`.
    let angle = |from: &Vec3, to: &Vec3| w.dot(&from.cross(to)).atan2(from.dot(to));
    let (peri, nu) = if e > 0.0 {
        (angle(&node_dir, &e_vec), angle(&e_vec, r))
    } else {
        (0.0, angle(&node_dir, r))
    };
    let (s, c) = nu.sin_cos();
    let mean_anomaly = if e < 1.0 {
        let ea = ((1.0 - e * e).sqrt() * s).atan2(e + c);
        (ea - e * ea.sin()).rem_euclid(tau)
    } else {
        let hyp = ((e * e - 1.0).sqrt() * s / (1.0 + e * c)).asinh();
        e * hyp.sinh() - hyp
    };
    Ok(ConicElements {
        perihelion: shape.perihelion,
        eccentricity: e,
        inclination: shape.inclination,
        node: node_dir.y.atan2(node_dir.x).rem_euclid(tau),
        argument_of_perihelion: peri.rem_euclid(tau),
        mean_anomaly,
    })
}

/// Bytes a population of `particles` needs (the members and a copy for the output tables).
pub fn population_bytes(particles: usize) -> u128 {
    particles as u128 * (Population::bytes_per_particle() as u128 + 200)
}

/// Refuses a population that does not fit in `available` bytes, before allocating it.
pub fn check_memory(particles: usize, available: Option<u64>) -> Result<(), SymplecticError> {
    let needed = population_bytes(particles);
    match available {
        Some(avail) if needed > u128::from(avail) => Err(SymplecticError::OutOfMemory {
            particles,
            needed_bytes: needed,
            available_bytes: avail,
        }),
        _ => Ok(()),
    }
}

pub use crate::guard::available_memory;

/// A short label of a status (`active`, `hill_sphere_<planet>`, `collision_<planet>` with the
/// planet's name, `collision_sun`, `perihelion`, `ejected`, `min_distance_<frame>` and
/// `max_distance_<frame>` with `heliocentric` or `barycentric`, `regularisation_lost`,
/// `failed`) and the removal time (NaN if active).
pub fn status_label(s: &ParticleStatus, planets: &Planets) -> (String, f64) {
    // A status of a later version of the enum (non-exhaustive) would need a label here.
    match s {
        ParticleStatus::Active => ("active".into(), f64::NAN),
        ParticleStatus::HillSphereEntry { time, planet, .. } => {
            (format!("hill_sphere_{}", planets.name(*planet)), *time)
        }
        ParticleStatus::Collision { time, planet, .. } => {
            (format!("collision_{}", planets.name(*planet)), *time)
        }
        ParticleStatus::PerihelionBelowLimit { time, .. } => ("perihelion".into(), *time),
        ParticleStatus::Ejected { time, .. } => ("ejected".into(), *time),
        ParticleStatus::SunCollision { time, .. } => ("collision_sun".into(), *time),
        ParticleStatus::InsideMinDistance { time, frame, .. } => {
            (format!("min_distance_{}", frame_label(*frame)), *time)
        }
        ParticleStatus::BeyondMaxDistance { time, frame, .. } => {
            (format!("max_distance_{}", frame_label(*frame)), *time)
        }
        ParticleStatus::RegularisationLost { time, .. } => ("regularisation_lost".into(), *time),
        ParticleStatus::IntegrationFailed { time, .. } => ("failed".into(), *time),
    }
}

/// `heliocentric` or `barycentric`.
fn frame_label(frame: DistanceFrame) -> &'static str {
    match frame {
        DistanceFrame::Heliocentric => "heliocentric",
        DistanceFrame::Barycentric => "barycentric",
    }
}
