//! `neighbour-search`: CSR neighbour lists, bounded in memory and interruptible.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use neighbour_search::{Method, NeighbourLists, SearchError, SearchLimits};

use crate::arrays::{available_memory_bytes, points, try_vec, Points};
use crate::interrupt::interruptible;
use crate::rust_err;

/// CSR arrays: offsets (N + 1) and indices.
type Csr<'py> = (Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<u32>>);

/// Bytes a pair may cost at the peak of a search: its `u32` index in a task's buffer
/// (which may have doubled past it) and again in the assembled lists.
const BYTES_PER_PAIR: usize = 12;

/// The pair limit of a call: the caller's, or else what the memory available holds.
fn pair_limit(max_pairs: Option<usize>) -> Option<usize> {
    max_pairs.or_else(|| available_memory_bytes().map(|b| b / BYTES_PER_PAIR))
}

/// Neighbour lists of `positions` within `radius`, as `(offsets, indices)` CSR arrays;
/// at most `max_pairs` pairs (default: what the memory available holds).
#[pyfunction]
#[pyo3(signature = (positions, radius, method = "cell-start-grid", max_pairs = None))]
fn neighbour_lists<'py>(
    py: Python<'py>,
    positions: &Bound<'py, PyAny>,
    radius: f64,
    method: &str,
    max_pairs: Option<usize>,
) -> PyResult<Csr<'py>> {
    let method: Method = method.parse().map_err(PyValueError::new_err)?;
    let points = points(positions, "positions")?;
    let interrupt = Arc::new(AtomicBool::new(false));
    let limits = SearchLimits {
        max_pairs: pair_limit(max_pairs),
        interrupt: Some(interrupt.clone()),
    };
    let stop = || interrupt.store(true, Ordering::Relaxed);
    let lists = interruptible(py, &stop, move || {
        let mut lists = NeighbourLists::with_limits(limits);
        match points {
            Points::F64(p) => method.build::<f64>().search(&p, radius, &mut lists),
            Points::F32(p) => method.build::<f32>().search(&p, radius as f32, &mut lists),
        }
        .map(|()| lists)
    })?;
    let lists = lists.map_err(|e| match e {
        SearchError::TooManyPairs { .. } => rust_err(format!(
            "neighbour_lists: {e} (max_pairs = {}{})",
            max_pairs.map_or_else(|| "the default".to_string(), |m| m.to_string()),
            if max_pairs.is_none() {
                ", from the memory available"
            } else {
                ""
            }
        )),
        e => rust_err(format!("neighbour_lists: {e}")),
    })?;
    let (offsets, indices) = lists.into_parts();
    let mut offsets_i64 = try_vec::<i64>("neighbour_lists: offsets", offsets.len())?;
    offsets_i64.extend(offsets.into_iter().map(|o| o as i64));
    Ok((offsets_i64.into_pyarray(py), indices.into_pyarray(py)))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(neighbour_lists, m)?)
}
