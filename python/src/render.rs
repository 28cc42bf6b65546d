//! `ssfr-render`: screen-space fluid images of particles.

use std::path::PathBuf;

use numpy::{IntoPyArray, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use sph_core::{Real, Vec3};
use ssfr_render::{RenderConfig, RenderParams, Renderer, RgbImage, SceneInfo, SsfrError};

use crate::arrays::{points, Points};
use crate::rust_err;

/// One image of `positions` with `params` (the call `cargo xtask run --render` makes).
pub(crate) fn render_image<R: Real>(
    params: &RenderParams,
    positions: &[Vec3<R>],
) -> Result<RgbImage, SsfrError> {
    let mut renderer = Renderer::default();
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

/// Renders `positions` with the `[render]` table given as JSON (`config_json`), framing
/// `tank` (min, max corners, m) or else the particles' bounding box.
#[pyfunction]
#[pyo3(signature = (positions, config_json, tank = None))]
fn render_json<'py>(
    py: Python<'py>,
    positions: &Bound<'py, PyAny>,
    config_json: &str,
    tank: Option<([f32; 3], [f32; 3])>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let config: RenderConfig =
        serde_json::from_str(config_json).map_err(|e| rust_err(format!("render options: {e}")))?;
    let points = points(positions, "positions")?;
    let image = py.detach(|| {
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
            Points::F64(p) => run(bounds(p), &|params| render_image(params, p)),
            Points::F32(p) => run(bounds(p), &|params| render_image(params, p)),
        }
    });
    to_numpy(py, image.map_err(rust_err)?)
}

/// Reads an 8-bit RGB PNG (as the renderer writes them) into an (H, W, 3) uint8 array.
#[pyfunction]
fn read_png(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyArray3<u8>>> {
    to_numpy(py, RgbImage::read_png(&path).map_err(rust_err)?)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render_json, m)?)?;
    m.add_function(wrap_pyfunction!(read_png, m)?)
}
