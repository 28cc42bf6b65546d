//! The events table ([`events_table`]): one row per event of every particle.

use std::sync::Arc;

use arrow_array::{BooleanArray, RecordBatch, StringArray, UInt64Array};

use super::tables::Columns;
use crate::{EventKind, ParticleStatus, Population, SymplecticError};

/// Name of the events table in a study's output directory.
pub const EVENTS_TABLE: &str = "events.parquet";

/// The table of the events of every particle ([`EventRules`](crate::EventRules)), in
/// member order and, per member, in the order detected (the close approaches still under
/// way last): `id`, `event` (`perihelion_below`, `tisserand_crossing`, `close_approach`),
/// `time_days` (the check that detected it; for a close approach the check of the smallest
/// distance), `threshold_au` and `perihelion_au` (a perihelion event: the value crossed and
/// the perihelion then), `tisserand_before` and `tisserand_after` (a crossing of `T_J = 3`:
/// `T_J` at the previous check and at this one), `planet` (a close approach: the planet's
/// name; empty otherwise), `min_distance_au` and `radius_au` (the smallest distance sampled
/// and the approach radius then), `ongoing` (a close approach of an active particle still
/// inside the radius: its minimum so far). A column that does not apply to a row holds NaN.
/// `events_dropped` in [`population_table`](super::population_table) counts the events a
/// full log did not keep.
pub fn events_table(population: &Population) -> Result<RecordBatch, SymplecticError> {
    let planets = population.ephemeris().planets();
    let (mut ids, mut kinds, mut planet, mut ongoing) = (vec![], vec![], vec![], vec![]);
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 7];
    for m in population.members() {
        let Some(log) = &m.events else { continue };
        for (event, open) in log.all_events() {
            let nan = f64::NAN;
            let (kind, name, values) = match event.kind {
                EventKind::PerihelionBelow {
                    threshold,
                    perihelion,
                } => (
                    "perihelion_below",
                    String::new(),
                    [threshold, perihelion, nan, nan, nan, nan],
                ),
                EventKind::TisserandCrossing { before, after } => (
                    "tisserand_crossing",
                    String::new(),
                    [nan, nan, before, after, nan, nan],
                ),
                EventKind::CloseApproach {
                    planet,
                    min_distance,
                    radius,
                } => (
                    "close_approach",
                    planets.name(planet).to_string(),
                    [nan, nan, nan, nan, min_distance, radius],
                ),
            };
            ids.push(m.id);
            kinds.push(kind);
            planet.push(name);
            ongoing.push(open && m.status == ParticleStatus::Active);
            cols[0].push(event.time);
            for (c, x) in cols[1..].iter_mut().zip(values) {
                c.push(x);
            }
        }
    }
    let names = [
        "time_days",
        "threshold_au",
        "perihelion_au",
        "tisserand_before",
        "tisserand_after",
        "min_distance_au",
        "radius_au",
    ];
    let mut table = Columns::default();
    table.push("id", Arc::new(UInt64Array::from(ids)));
    table.push("event", Arc::new(StringArray::from(kinds)));
    table.floats(&names, cols);
    table.push("planet", Arc::new(StringArray::from(planet)));
    table.push("ongoing", Arc::new(BooleanArray::from(ongoing)));
    table.batch()
}
