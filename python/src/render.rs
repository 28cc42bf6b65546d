//! `ssfr-render`: screen-space fluid images of particles, and PNG files.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use numpy::{IntoPyArray, PyArray3, PyArrayDescrMethods, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyString};
use sph_core::{Real, Vec3};
use ssfr_render::{RenderConfig, RenderParams, Renderer, RgbImage, SceneInfo, SsfrError};

use crate::arrays::{as_array, check_fits, check_shape, points, Points};
use crate::interrupt::interruptible;
use crate::rust_err;

/// Largest |coordinate| (m) the renderer frames: its arithmetic is float32, whose squares
/// overflow (3.4·10³⁸) beyond about 1.8·10¹⁹; 10¹⁸ leaves room for sums of three squares
/// and for the camera's distance.
const MAX_COORDINATE_M: f64 = 1e18;

/// One image of `positions` with `params` (the call `cargo xtask run --render` makes).
pub(crate) fn render_image<R: Real>(
    params: &RenderParams,
    positions: &[Vec3<R>],
    cancel: Option<Arc<AtomicBool>>,
) -> Result<RgbImage, SsfrError> {
    let mut renderer = Renderer::default();
    renderer.set_cancel(cancel);
    renderer.render_points(params, positions)?;
    Ok(renderer.image())
}

/// An image as an (H, W, 3) uint8 array.
pub(crate) fn to_numpy(py: Python<'_>, image: RgbImage) -> PyResult<Bound<'_, PyArray3<u8>>> {
    let (w, h) = (image.width, image.height);
    image.data.into_pyarray(py).reshape([h, w, 3])
}

fn bounds<R: Real>(p: &[Vec3<R>]) -> Option<([f32; 3], [f32; 3])> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for q in p {
        for a in 0..3 {
            let x = q[a].as_f64() as f32;
            lo[a] = lo[a].min(x);
            hi[a] = hi[a].max(x);
        }
    }
    (!p.is_empty()).then_some((lo, hi))
}

/// The first particle with a finite coordinate beyond [`MAX_COORDINATE_M`], as an error
/// naming it (non-finite ones are the renderer's to report, by index too).
fn check_range<R: Real>(p: &[Vec3<R>]) -> PyResult<()> {
    for (i, q) in p.iter().enumerate() {
        for (a, axis) in ['x', 'y', 'z'].into_iter().enumerate() {
            let x = q[a].as_f64();
            if x.is_finite() && x.abs() > MAX_COORDINATE_M {
                return Err(rust_err(format!(
                    "render: positions: particle {i}: coordinate {axis} = {x:e} m is beyond \
                     ±{MAX_COORDINATE_M:e} m, more than the renderer's float32 arithmetic \
                     can frame"
                )));
            }
        }
    }
    Ok(())
}

/// A Python option value as TOML (the `[render]` table's own format, which carries NaN
/// and infinities as the values they are): dicts with string keys (entries that are
/// `None` left out, i.e. defaulted), sequences and arrays, booleans, integers (numpy's
/// included), floats and strings. `path` names the value in errors.
fn to_toml(v: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() || v.is_instance(&numpy_bool(v.py())?)? {
        return Ok(toml::Value::Boolean(v.is_truthy()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, x) in d.iter() {
            let key: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!("{path}: keys must be strings, got {k:?}"))
            })?;
            if x.is_none() {
                continue;
            }
            let sub = format!("{path}[{key:?}]");
            table.insert(key, to_toml(&x, &sub)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    // Integers, Python's and numpy's (anything with __index__).
    if let Ok(i) = v.extract::<i64>() {
        return Ok(toml::Value::Integer(i));
    }
    // numpy floating scalars and other numbers with __float__.
    if v.hasattr("__float__")? && !v.hasattr("__len__")? {
        return Ok(toml::Value::Float(v.extract::<f64>()?));
    }
    if v.hasattr("__len__")? {
        let array = as_array(v, path)?;
        check_fits(path, array.len(), 8)?;
        let list = array.call_method0("tolist")?;
        let mut items = Vec::new();
        for (k, x) in list.try_iter()?.enumerate() {
            items.push(to_toml(&x?, &format!("{path}[{k}]"))?);
        }
        return Ok(toml::Value::Array(items));
    }
    let ty = v.get_type().name()?;
    Err(PyTypeError::new_err(format!(
        "{path}: expected a number, string, sequence or dict, got {ty}"
    )))
}

fn numpy_bool(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    py.import("numpy")?.getattr("bool_")
}

/// The options dict as a [`RenderConfig`], errors naming the option by its keyword
/// (`background["colour_of_sky"]`: unknown field), never a position in text the caller
/// did not write.
fn config_from(options: &Bound<'_, PyDict>) -> PyResult<RenderConfig> {
    let value = to_toml(options.as_any(), "options")?;
    serde_path_to_error::deserialize::<_, RenderConfig>(value).map_err(|e| {
        let path = keyword_path(&e.path().to_string());
        // The message's first line: toml adds the table (`in `background``), which the
        // path already says.
        let inner = e.into_inner().to_string();
        let inner = inner.lines().next().unwrap_or_default().trim_end();
        if path.is_empty() {
            rust_err(format!("render: {inner}"))
        } else {
            rust_err(format!("render: {path}: {inner}"))
        }
    })
}

/// A field path of the `[render]` table as the Python caller named it: `particle_radius`
/// is the `radius` argument; the root (`.`) is empty.
fn keyword_path(path: &str) -> String {
    match path {
        "." => String::new(),
        "particle_radius" => "radius".into(),
        p => p.to_string(),
    }
}

/// A renderer error, with a `[render]` field path spoken of by its keyword.
fn render_err(e: SsfrError) -> PyErr {
    match e {
        SsfrError::Config { field, reason } => {
            rust_err(format!("render: {}: {reason}", keyword_path(&field)))
        }
        e => rust_err(format!("render: {e}")),
    }
}

/// Renders `positions` (N, 3) with spheres of `radius` (m) and the other `[render]`
/// options as a dict (`options`), framing `tank` (min, max corners, m) or else the
/// particles' bounding box.
#[pyfunction]
#[pyo3(signature = (positions, radius, options, tank = None))]
fn render_options<'py>(
    py: Python<'py>,
    positions: &Bound<'py, PyAny>,
    radius: f64,
    options: &Bound<'py, PyDict>,
    tank: Option<([f32; 3], [f32; 3])>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let mut config = config_from(options)?;
    config.particle_radius = Some(radius as f32);
    let points = points(positions, "positions")?;
    match &points {
        Points::F64(p) => check_range(p)?,
        Points::F32(p) => check_range(p)?,
    }
    // Ctrl-C raises the flag the renderer checks per particle and per band of rows, and
    // the call waits for it to stop before raising.
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    let stop = move || flag.store(true, Ordering::Relaxed);
    let image = interruptible(py, &stop, move || {
        let run = |liquid, f: &dyn Fn(&RenderParams) -> Result<RgbImage, SsfrError>| {
            let info = SceneInfo {
                tank,
                liquid,
                particle_spacing: config.particle_radius.unwrap_or(1.0)
                    / ssfr_render::RADIUS_OVER_SPACING,
                obstacles: Vec::new(),
            };
            f(&config.resolve(&info)?)
        };
        match &points {
            Points::F64(p) => run(bounds(p), &|params| {
                render_image(params, p, Some(cancel.clone()))
            }),
            Points::F32(p) => run(bounds(p), &|params| {
                render_image(params, p, Some(cancel.clone()))
            }),
        }
    })?;
    to_numpy(py, image.map_err(render_err)?)
}

/// Reads an 8-bit RGB PNG (as the renderer writes them) into an (H, W, 3) uint8 array.
#[pyfunction]
fn read_png(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyArray3<u8>>> {
    to_numpy(py, RgbImage::read_png(&path).map_err(rust_err)?)
}

/// Writes an (H, W, 3) uint8 image (or any array-like numpy converts to one exactly) to
/// `path` as an 8-bit RGB PNG, atomically (a complete file or none).
#[pyfunction]
fn write_png(py: Python<'_>, path: PathBuf, image: &Bound<'_, PyAny>) -> PyResult<()> {
    let array = as_array(image, "image")?;
    check_shape(&array, "image", "(H, W, 3)", Some(3), Some(3))?;
    let shape = array.shape().to_vec();
    let (height, width) = (shape[0], shape[1]);
    ssfr_render::check_image_size(width, height)
        .map_err(|e| PyValueError::new_err(format!("image: {e}")))?;
    let dtype = array.dtype();
    let array = if dtype.is_equiv_to(&numpy::dtype::<u8>(py)) {
        array
    } else if matches!(dtype.kind(), b'i' | b'u' | b'b') {
        // Integers as numpy would store them in uint8, refused if any would change.
        let np = py.import("numpy")?;
        let in_range: bool = np
            .call_method1(
                "all",
                (array.call_method1("__eq__", (array.call_method1("astype", ("uint8",))?,))?,),
            )?
            .extract()?;
        if !in_range {
            return Err(PyValueError::new_err(format!(
                "image: values of dtype {dtype} outside 0..=255 (an 8-bit image)"
            )));
        }
        array.call_method1("astype", ("uint8",))?.cast_into()?
    } else {
        return Err(PyTypeError::new_err(format!(
            "image: expected uint8 (or integers in 0..=255), got dtype {dtype}"
        )));
    };
    check_fits("image", width.saturating_mul(height), 3)?;
    let a: numpy::PyReadonlyArray3<'_, u8> = array.extract()?;
    let data: Vec<u8> = a.as_array().iter().copied().collect();
    let img = RgbImage {
        width,
        height,
        data,
    };
    py.detach(|| img.write_png(&path)).map_err(rust_err)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render_options, m)?)?;
    m.add_function(wrap_pyfunction!(read_png, m)?)?;
    m.add_function(wrap_pyfunction!(write_png, m)?)
}
