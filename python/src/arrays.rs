//! numpy arrays in: shape and dtype checked with messages naming the argument.

use numpy::{PyArrayDescrMethods, PyReadonlyArray2, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use sph_core::Vec3;

/// Points `(N, 3)` as the caller gave them: float64 or float32.
pub(crate) enum Points {
    /// float64 points.
    F64(Vec<Vec3<f64>>),
    /// float32 points.
    F32(Vec<Vec3<f32>>),
}

/// The floating-point type of a numpy array: `true` for float64, `false` for float32, a
/// `TypeError` naming `what` otherwise.
pub(crate) fn is_f64(array: &Bound<'_, PyUntypedArray>, what: &str) -> PyResult<bool> {
    let dtype = array.dtype();
    let py = array.py();
    if dtype.is_equiv_to(&numpy::dtype::<f64>(py)) {
        Ok(true)
    } else if dtype.is_equiv_to(&numpy::dtype::<f32>(py)) {
        Ok(false)
    } else {
        Err(PyTypeError::new_err(format!(
            "{what}: expected a float64 or float32 array, got dtype {dtype}"
        )))
    }
}

/// `obj` as a numpy array, or a `TypeError` naming `what`.
pub(crate) fn untyped<'a, 'py>(
    obj: &'a Bound<'py, PyAny>,
    what: &str,
) -> PyResult<&'a Bound<'py, PyUntypedArray>> {
    obj.cast::<PyUntypedArray>().map_err(|_| {
        let ty = obj
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string());
        PyTypeError::new_err(format!("{what}: expected a numpy array, got {ty}"))
    })
}

/// Checks that `array` has `ndim` dimensions and, if given, `last` entries along the last
/// one.
pub(crate) fn check_shape(
    array: &Bound<'_, PyUntypedArray>,
    what: &str,
    expected: &str,
    ndim: Option<usize>,
    last: Option<usize>,
) -> PyResult<()> {
    let shape = array.shape();
    let bad_ndim = ndim.is_some_and(|n| shape.len() != n);
    let bad_last = last.is_some_and(|l| shape.last() != Some(&l));
    if bad_ndim || bad_last {
        return Err(PyValueError::new_err(format!(
            "{what}: expected shape {expected}, got {shape:?}"
        )));
    }
    Ok(())
}

fn rows<T: numpy::Element + Copy + sph_core::Real>(
    obj: &Bound<'_, PyAny>,
) -> PyResult<Vec<Vec3<T>>> {
    let a: PyReadonlyArray2<'_, T> = obj.extract()?;
    let a = a.as_array();
    Ok(a.rows()
        .into_iter()
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect())
}

/// `(N, 3)` points (float64 or float32) copied out of `obj`.
pub(crate) fn points(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Points> {
    let array = untyped(obj, what)?;
    check_shape(array, what, "(N, 3)", Some(2), Some(3))?;
    Ok(if is_f64(array, what)? {
        Points::F64(rows::<f64>(obj)?)
    } else {
        Points::F32(rows::<f32>(obj)?)
    })
}
