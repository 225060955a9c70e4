//! `import dancegen`: the Python package's native module (`dancegen._dancegen`), built with
//! PyO3 and maturin (`pip install ./crates/dancegen-py`). Arrays in and out are numpy arrays
//! (float32, C order); every long call runs without the GIL; errors are `DancegenError` with
//! the CLI's words. The Python side (`python/dancegen/`) adds keyword handling, the
//! `metrics` and `io` modules and the type stubs.

mod arrays;
mod eval;
mod generate;
mod io;
mod music;

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    _dancegen,
    DancegenError,
    PyException,
    "dancegen refused or failed; the message says why, in the CLI's words."
);

/// A `DancegenError` with `e`'s words.
pub(crate) fn fail(e: impl std::fmt::Display) -> PyErr {
    DancegenError::new_err(e.to_string())
}

/// A `DancegenError` with an error chain's words, outermost first (as the CLI prints them).
pub(crate) fn fail_chain(e: anyhow::Error) -> PyErr {
    DancegenError::new_err(format!("{e:#}"))
}

#[pymodule]
fn _dancegen(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("DancegenError", m.py().get_type::<DancegenError>())?;
    m.add_function(wrap_pyfunction!(music::features, m)?)?;
    m.add_function(wrap_pyfunction!(music::beats, m)?)?;
    m.add_function(wrap_pyfunction!(eval::evaluate_json, m)?)?;
    m.add_class::<io::Motion>()?;
    m.add_function(wrap_pyfunction!(io::read, m)?)?;
    m.add_function(wrap_pyfunction!(io::smpl, m)?)?;
    m.add_function(wrap_pyfunction!(io::joints, m)?)?;
    m.add_function(wrap_pyfunction!(io::smpl_fk, m)?)?;
    m.add_class::<generate::Dance>()?;
    m.add_function(wrap_pyfunction!(generate::generate_named, m)?)?;
    Ok(())
}
