//! numpy arrays in: array-likes converted as numpy converts them, shape, dtype and size
//! checked (before any copy) with messages naming the argument.

use numpy::{PyArrayDescrMethods, PyReadonlyArray2, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sph_core::Vec3;

use crate::rust_err;

/// Points `(N, 3)` as the caller gave them: float64 or float32.
pub(crate) enum Points {
    /// float64 points.
    F64(Vec<Vec3<f64>>),
    /// float32 points.
    F32(Vec<Vec3<f32>>),
}

/// Bytes of memory this process may still allocate ([`sph_core::memory::available_bytes`]:
/// the kernel's `MemAvailable`, within the address-space limit), or `None` where it is not
/// known.
pub(crate) fn available_memory_bytes() -> Option<usize> {
    sph_core::memory::available_bytes().map(|b| usize::try_from(b).unwrap_or(usize::MAX))
}

/// `bytes` as "1.2 GB" (decimal units).
pub(crate) fn human_bytes(bytes: f64) -> String {
    const UNITS: [&str; 5] = ["bytes", "kB", "MB", "GB", "TB"];
    let mut v = bytes;
    let mut u = 0;
    while v >= 1000.0 && u + 1 < UNITS.len() {
        v /= 1000.0;
        u += 1;
    }
    if u == 0 {
        format!("{v:.0} {}", UNITS[0])
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// Refuses, with a [`crate::PartisimError`] naming `what` and both sizes, a buffer of
/// `count` elements of `bytes_each` bytes that would not fit in the memory available.
pub(crate) fn check_fits(what: &str, count: usize, bytes_each: usize) -> PyResult<()> {
    let need = count as f64 * bytes_each as f64;
    let too_big = match available_memory_bytes() {
        Some(have) => need > have as f64,
        None => need > isize::MAX as f64,
    };
    if too_big {
        let have = available_memory_bytes()
            .map_or_else(|| "unknown".to_string(), |b| human_bytes(b as f64));
        return Err(rust_err(format!(
            "{what}: {count} × {bytes_each} bytes = {} needed; memory available: {have}",
            human_bytes(need)
        )));
    }
    Ok(())
}

/// A `Vec` of `count` elements allocated fallibly, or a [`crate::PartisimError`] naming
/// `what` and the size.
pub(crate) fn try_vec<T>(what: &str, count: usize) -> PyResult<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(count).map_err(|e| {
        rust_err(format!(
            "{what}: could not allocate {} for {count} elements: {e}",
            human_bytes(count as f64 * std::mem::size_of::<T>() as f64)
        ))
    })?;
    Ok(v)
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

/// `obj` as a numpy array, or a `TypeError` naming `what` (no conversion: for callers that
/// take arrays only).
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

/// `obj` as a numpy array: an array as it is (views included, no copy), anything else
/// through `numpy.asarray` (lists, tuples, scalars, objects with `__array__`), with
/// numpy's complaint (ragged lists, say) raised as a `ValueError` naming `what`.
pub(crate) fn as_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj,)).map_err(|e| {
        let ty = obj
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string());
        PyValueError::new_err(format!(
            "{what}: a {ty} that numpy cannot make an array of numbers of: {e}"
        ))
    })?;
    Ok(a.cast_into::<PyUntypedArray>()?)
}

/// `array` as float64 or float32, converting as `numpy.asarray(array, dtype=float64)`
/// does for other real numbers (integers, booleans, other float widths or byte orders);
/// a `TypeError` naming `what` and the dtype for anything else (complex, strings,
/// objects). The conversion copies: call it after the size checks. Returns the array and
/// whether it is float64.
pub(crate) fn as_float<'py>(
    array: Bound<'py, PyUntypedArray>,
    what: &str,
) -> PyResult<(Bound<'py, PyUntypedArray>, bool)> {
    if let Ok(f64) = is_f64(&array, what) {
        return Ok((array, f64));
    }
    let dtype = array.dtype();
    let kind = dtype.kind();
    if !matches!(kind, b'b' | b'i' | b'u' | b'f') {
        return Err(PyTypeError::new_err(format!(
            "{what}: expected real numbers (float64 or float32 as they are, integers \
             converted to float64), got dtype {dtype}"
        )));
    }
    let kwargs = PyDict::new(array.py());
    kwargs.set_item("dtype", "float64")?;
    let converted = array.call_method("astype", (), Some(&kwargs))?;
    Ok((converted.cast_into::<PyUntypedArray>()?, true))
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
    array: &Bound<'_, PyUntypedArray>,
    what: &str,
) -> PyResult<Vec<Vec3<T>>> {
    let a: PyReadonlyArray2<'_, T> = array.extract()?;
    let a = a.as_array();
    let mut out = try_vec(what, a.nrows())?;
    out.extend(a.rows().into_iter().map(|r| Vec3::new(r[0], r[1], r[2])));
    Ok(out)
}

/// `(N, 3)` points copied out of `obj`: float64 or float32 as given, other real numbers
/// and array-likes converted to float64 as numpy converts them. Shape, then size (against
/// the memory available, before any copy: a broadcast view of 10¹⁰ rows is refused by its
/// element count), then dtype are checked, each error naming `what`.
pub(crate) fn points(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Points> {
    let array = as_array(obj, what)?;
    check_shape(&array, what, "(N, 3)", Some(2), Some(3))?;
    let n = array.shape()[0];
    let bytes_each = if is_f64(&array, what).unwrap_or(true) {
        // Points as float64 (and, for a conversion, the converted array besides).
        if array.dtype().is_equiv_to(&numpy::dtype::<f64>(obj.py())) {
            24
        } else {
            48
        }
    } else {
        12
    };
    check_fits(what, n, bytes_each)?;
    let (array, f64) = as_float(array, what)?;
    Ok(if f64 {
        Points::F64(rows::<f64>(&array, what)?)
    } else {
        Points::F32(rows::<f32>(&array, what)?)
    })
}
