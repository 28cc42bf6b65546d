//! `neighbour-search`: CSR neighbour lists.

use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use neighbour_search::{Method, NeighbourLists};

use crate::arrays::{points, Points};
use crate::rust_err;

/// CSR arrays: offsets (N + 1) and indices.
type Csr<'py> = (Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<u32>>);

/// Neighbour lists of `positions` within `radius`, as `(offsets, indices)` CSR arrays.
#[pyfunction]
#[pyo3(signature = (positions, radius, method = "cell-start-grid"))]
fn neighbour_lists<'py>(
    py: Python<'py>,
    positions: &Bound<'py, PyAny>,
    radius: f64,
    method: &str,
) -> PyResult<Csr<'py>> {
    let method: Method = method.parse().map_err(PyValueError::new_err)?;
    let points = points(positions, "positions")?;
    let lists = py.detach(|| {
        let mut lists = NeighbourLists::new();
        match points {
            Points::F64(p) => method.build::<f64>().search(&p, radius, &mut lists),
            Points::F32(p) => method.build::<f32>().search(&p, radius as f32, &mut lists),
        }
        .map(|()| lists)
    });
    let (offsets, indices) = lists.map_err(rust_err)?.into_parts();
    let offsets: Vec<i64> = offsets.into_iter().map(|o| o as i64).collect();
    Ok((offsets.into_pyarray(py), indices.into_pyarray(py)))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(neighbour_lists, m)?)
}
