//! `partisim._partisim`: the Python extension module over the workspace's crates (pyo3 +
//! numpy, built by maturin). A thin layer: one file per crate, arrays converted at the
//! boundary, every long call run with the GIL released, every Rust error raised as
//! [`PartisimError`] carrying the Rust message.

mod arrays;
mod comets;
mod interrupt;
mod kernels;
mod measure;
mod neighbours;
mod render;
mod sim;

use pyo3::prelude::*;

pyo3::create_exception!(
    partisim,
    PartisimError,
    pyo3::exceptions::PyException,
    "An error reported by the Rust crates; the message is the Rust error's."
);

/// A Rust error as a Python [`PartisimError`] with the Rust message.
pub(crate) fn rust_err(e: impl std::fmt::Display) -> PyErr {
    PartisimError::new_err(e.to_string())
}

#[pymodule]
fn _partisim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("PartisimError", m.py().get_type::<PartisimError>())?;
    neighbours::register(m)?;
    kernels::register(m)?;
    sim::register(m)?;
    render::register(m)?;
    comets::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
