//! The output tables (feature `parquet`): the population table ([`population_table`]) and
//! the writer of any table as Apache Parquet ([`write_parquet`]).

use std::path::Path;
use std::sync::Arc;

use arrow_array::{ArrayRef, BooleanArray, Float64Array, RecordBatch, StringArray, UInt64Array};
use arrow_schema::{Field, Schema};

use super::status_label;
use crate::classes::{
    inclination_to_plane, jupiter_orbit_normal, levison_class, orbital_region, tisserand_jupiter,
};
use crate::{ParticleStatus, Population, SymplecticError};

/// The table of every particle now: `id`, `status`, `time_days` (the particle's own time:
/// the steps are variable, so each particle is at the first step end at or after the
/// snapshot time), `removal_time_days` (NaN if active), barycentric osculating `a_au`, `e`,
/// `i_deg` (to the frame's reference plane), `q_au`, the barycentric state
/// `x_au … vz_au_per_day`, the Tisserand parameter with respect to Jupiter
/// `tisserand_jupiter` (with the inclination to Jupiter's orbital plane,
/// [`tisserand_jupiter`]; NaN if unbound), the region by
/// perihelion and semi-major axis `region` ([`orbital_region`]:
/// `trans_neptunian`, `centaur`, `perihelion_inside_jupiter`, `unbound`), Levison's (1996)
/// class `levison_class` ([`levison_class`]:
/// `jupiter_family`, `encke_type`, `chiron_type`, `halley_type`, `long_period`,
/// `unclassified`),
/// and `in_encounter` (whether the particle, active, is being integrated through an
/// encounter; `false` for every removed particle) and `encounters_begun` (its switches to
/// the encounter mode so far, [`PopulationMember::encounters_begun`](crate::PopulationMember)),
/// `planet_encounters`, `planet_encounter_switches` and `max_switches_per_encounter` (its
/// close encounters with the planets, the switches in them and the most in one:
/// [`EncounterTally`](crate::EncounterTally)), and `events_dropped` (events its full log did not keep, [`EventLog::dropped`](crate::EventLog);
/// the events themselves are in [`events_table`](super::events_table)).
pub fn population_table(population: &Population) -> Result<RecordBatch, SymplecticError> {
    let members = population.members();
    let n = members.len();
    let mut cols: Vec<Vec<f64>> = (0..13).map(|_| Vec::with_capacity(n)).collect();
    let mut status = Vec::with_capacity(n);
    let (mut region, mut levison) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let jupiter_normal = jupiter_orbit_normal(population.ephemeris());
    for (i, m) in members.iter().enumerate() {
        let el = population.elements(i)?;
        let q = population.barycentric_position(i);
        let v = m.particle.velocity;
        let (label, removal_time) = status_label(&m.status, population.ephemeris().planets());
        status.push(label);
        let i_jupiter = jupiter_normal.map_or(f64::NAN, |n| inclination_to_plane(&q, &v, &n));
        let t_j = tisserand_jupiter(el.semi_major_axis, el.eccentricity, i_jupiter);
        region.push(orbital_region(&el).label());
        levison.push(levison_class(el.semi_major_axis, el.eccentricity, t_j).label());
        let row = [
            m.particle.time,
            removal_time,
            el.semi_major_axis,
            el.eccentricity,
            el.inclination.to_degrees(),
            el.perihelion,
            q.x,
            q.y,
            q.z,
            v.x,
            v.y,
            v.z,
            t_j,
        ];
        for (c, x) in cols.iter_mut().zip(row) {
            c.push(x);
        }
    }
    let names = [
        "time_days",
        "removal_time_days",
        "a_au",
        "e",
        "i_deg",
        "q_au",
        "x_au",
        "y_au",
        "z_au",
        "vx_au_per_day",
        "vy_au_per_day",
        "vz_au_per_day",
        "tisserand_jupiter",
    ];
    let mut table = Columns::default();
    table.push(
        "id",
        Arc::new(UInt64Array::from_iter_values(members.iter().map(|m| m.id))),
    );
    table.push("status", Arc::new(StringArray::from(status)));
    table.floats(&names, cols);
    table.push("region", Arc::new(StringArray::from(region)));
    table.push("levison_class", Arc::new(StringArray::from(levison)));
    table.push(
        "in_encounter",
        Arc::new(BooleanArray::from_iter(
            // Active members only: a removed member is in no encounter (a checkpoint of an
            // earlier version may still hold the encounter state it was removed in).
            members
                .iter()
                .map(|m| Some(m.status == ParticleStatus::Active && m.encounter.is_some())),
        )),
    );
    table.push(
        "encounters_begun",
        Arc::new(UInt64Array::from_iter_values(
            members.iter().map(|m| u64::from(m.encounters_begun)),
        )),
    );
    let tally = |f: fn(&crate::EncounterTally) -> u32| {
        Arc::new(UInt64Array::from_iter_values(
            members.iter().map(|m| u64::from(f(&m.tally))),
        ))
    };
    table.push("planet_encounters", tally(|t| t.encounters));
    table.push("planet_encounter_switches", tally(|t| t.switches));
    table.push("max_switches_per_encounter", tally(|t| t.max_switches));
    table.push(
        "events_dropped",
        Arc::new(UInt64Array::from_iter_values(
            members
                .iter()
                .map(|m| m.events.as_ref().map_or(0, |log| log.dropped)),
        )),
    );
    table.batch()
}

/// The columns of a table being built, in order (every column non-nullable).
#[derive(Default)]
pub(crate) struct Columns {
    fields: Vec<Field>,
    arrays: Vec<ArrayRef>,
}

impl Columns {
    /// Appends the column `name`.
    pub(crate) fn push(&mut self, name: &str, array: ArrayRef) {
        self.fields
            .push(Field::new(name, array.data_type().clone(), false));
        self.arrays.push(array);
    }

    /// Appends one `f64` column per name.
    pub(crate) fn floats(&mut self, names: &[&str], columns: Vec<Vec<f64>>) {
        for (name, c) in names.iter().zip(columns) {
            self.push(name, Arc::new(Float64Array::from(c)));
        }
    }

    /// The table.
    pub(crate) fn batch(self) -> Result<RecordBatch, SymplecticError> {
        RecordBatch::try_new(Arc::new(Schema::new(self.fields)), self.arrays).map_err(|e| {
            SymplecticError::Output {
                path: String::new(),
                reason: e.to_string(),
            }
        })
    }
}

/// Writes `batch` to `path` as Parquet (Snappy pages), atomically: a temporary file, `fsync`,
/// rename.
pub fn write_parquet(path: &Path, batch: &RecordBatch) -> Result<(), SymplecticError> {
    let err = |e: String| SymplecticError::Output {
        path: path.display().to_string(),
        reason: e,
    };
    let file = atomic_write_file::AtomicWriteFile::open(path).map_err(|e| err(e.to_string()))?;
    let props = parquet::file::properties::WriterProperties::builder()
        .set_compression(parquet::basic::Compression::SNAPPY)
        .build();
    let mut writer = parquet::arrow::ArrowWriter::try_new(file, batch.schema(), Some(props))
        .map_err(|e| err(e.to_string()))?;
    writer.write(batch).map_err(|e| err(e.to_string()))?;
    let file = writer.into_inner().map_err(|e| err(e.to_string()))?;
    file.commit().map_err(|e| err(e.to_string()))
}
