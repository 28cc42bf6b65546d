//! `sph-kernels`: smoothing kernels evaluated over numpy arrays.

use numpy::ndarray::{ArrayD, Axis};
use numpy::{IntoPyArray, PyReadonlyArrayDyn, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;
use sph_kernels::{AnyKernel, Kernel as _, KernelKind};

use crate::arrays::{as_array, as_float, check_fits, check_shape};
use crate::rust_err;

/// A smoothing kernel `W(r, h)` of support radius `h` (m), evaluated elementwise.
#[pyclass(module = "partisim", frozen)]
struct Kernel {
    f64: AnyKernel<f64>,
    f32: AnyKernel<f32>,
}

/// `obj` (any array-like of real numbers) as a float64 or float32 array named `what`, after
/// checking that its values, as float64, fit in the memory available (a broadcast view
/// is refused by its element count before anything is copied).
fn real_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
    vector: bool,
) -> PyResult<(Bound<'py, PyUntypedArray>, bool)> {
    let a = as_array(obj, what)?;
    if vector {
        check_shape(&a, what, "(..., 3)", None, Some(3))?;
    }
    // The result, and for a conversion the converted input besides.
    check_fits(what, a.len(), 16)?;
    as_float(a, what)
}

fn values<R: numpy::Element + sph_core::Real>(
    py: Python<'_>,
    r: &Bound<'_, PyUntypedArray>,
    f: impl Fn(R) -> R,
) -> PyResult<Py<PyAny>> {
    let r: PyReadonlyArrayDyn<'_, R> = r.extract()?;
    let out: ArrayD<R> = r.as_array().mapv(f);
    Ok(out.into_pyarray(py).into_any().unbind())
}

fn gradients<R: numpy::Element + sph_core::Real>(
    py: Python<'_>,
    r: &Bound<'_, PyUntypedArray>,
    k: &AnyKernel<R>,
) -> PyResult<Py<PyAny>> {
    let r: PyReadonlyArrayDyn<'_, R> = r.extract()?;
    let r = r.as_array();
    let mut out = ArrayD::<R>::zeros(r.shape());
    let last = Axis(r.ndim() - 1);
    for (src, mut dst) in r.lanes(last).into_iter().zip(out.lanes_mut(last)) {
        let g = k.gradient(&sph_core::Vec3::new(src[0], src[1], src[2]));
        dst.iter_mut().zip(g.iter()).for_each(|(d, s)| *d = *s);
    }
    Ok(out.into_pyarray(py).into_any().unbind())
}

impl Kernel {
    /// `f64` or `f32` applied to each element of `r`, by its dtype.
    fn elementwise(
        &self,
        py: Python<'_>,
        r: &Bound<'_, PyAny>,
        f64: impl Fn(&AnyKernel<f64>, f64) -> f64,
        f32: impl Fn(&AnyKernel<f32>, f32) -> f32,
    ) -> PyResult<Py<PyAny>> {
        let (r, is_f64) = real_array(r, "r", false)?;
        if is_f64 {
            values::<f64>(py, &r, |x| f64(&self.f64, x))
        } else {
            values::<f32>(py, &r, |x| f32(&self.f32, x))
        }
    }
}

#[pymethods]
impl Kernel {
    /// The kernel's name.
    #[getter]
    fn name(&self) -> &'static str {
        self.f64.name()
    }

    /// The support radius h (m).
    #[getter]
    fn support_radius(&self) -> f64 {
        self.f64.support_radius()
    }

    /// W(r) (1/m³) for distances r (m) of any shape, float64 or float32.
    fn value(&self, py: Python<'_>, r: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.elementwise(py, r, |k, x| k.value(x), |k, x| k.value(x))
    }

    /// dW/dr (1/m⁴) for distances r (m) of any shape.
    fn derivative(&self, py: Python<'_>, r: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.elementwise(py, r, |k, x| k.derivative(x), |k, x| k.derivative(x))
    }

    /// ∇W (1/m⁴) for difference vectors r_vectors (m) of shape (..., 3).
    fn gradient(&self, py: Python<'_>, r_vectors: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        let (a, is_f64) = real_array(r_vectors, "r_vectors", true)?;
        if is_f64 {
            gradients(py, &a, &self.f64)
        } else {
            gradients(py, &a, &self.f32)
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "kernel({:?}, support_radius={})",
            self.f64.name(),
            self.f64.support_radius()
        )
    }
}

/// The kernel `name` (poly6, spiky, viscosity, cubic-spline, wendland-c2) of support
/// radius `support_radius` (m).
#[pyfunction]
fn kernel(name: &str, support_radius: f64) -> PyResult<Kernel> {
    let kind: KernelKind = name.parse().map_err(rust_err)?;
    Ok(Kernel {
        f64: kind.build(support_radius).map_err(rust_err)?,
        f32: kind.build(support_radius as f32).map_err(rust_err)?,
    })
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Kernel>()?;
    m.add_function(wrap_pyfunction!(kernel, m)?)
}
