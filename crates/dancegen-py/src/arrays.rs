//! numpy arrays in and out: float32 (or float64) in, any memory order; float32 out, C order.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::fail;

/// A float32 array of `shape` holding `data` (moved into numpy, not copied).
pub fn to_numpy<'py>(
    py: Python<'py>,
    shape: &[usize],
    data: Vec<f32>,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(PyArray1::from_vec(py, data).reshape(shape)?.into_any())
}

/// `(shape, values)` of a float32 or float64 numpy array `what` (named in errors), values in
/// C order.
pub fn values<T: From<f32> + Copy + 'static>(
    obj: &Bound<'_, PyAny>,
    what: &str,
    from_f64: fn(f64) -> T,
) -> PyResult<(Vec<usize>, Vec<T>)> {
    // A C-ordered array is read as one slice; any other order (Fortran order is contiguous
    // too, but its slice is not in C order) element by element, slower.
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'_, f32>>() {
        let shape = a.shape().to_vec();
        let data = match a.as_slice() {
            Ok(s) if a.is_c_contiguous() => s.iter().map(|&v| T::from(v)).collect(),
            _ => a.as_array().iter().map(|&v| T::from(v)).collect(),
        };
        return Ok((shape, data));
    }
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'_, f64>>() {
        let shape = a.shape().to_vec();
        let data = match a.as_slice() {
            Ok(s) if a.is_c_contiguous() => s.iter().map(|&v| from_f64(v)).collect(),
            _ => a.as_array().iter().map(|&v| from_f64(v)).collect(),
        };
        return Ok((shape, data));
    }
    let kind = obj
        .getattr("dtype")
        .map(|d| format!("an array of {d}"))
        .unwrap_or_else(|_| {
            format!(
                "a {}",
                obj.get_type().name().map_or("?".into(), |n| n.to_string())
            )
        });
    Err(fail(format!(
        "{what}: expected a numpy array of float32 or float64, got {kind}"
    )))
}

/// [`values`] as float32 (float64 input rounded to float32, as the `.npy` files hold it).
pub fn f32_values(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<usize>, Vec<f32>)> {
    values(obj, what, |v| v as f32)
}

/// [`values`] as float64 (float32 input widened exactly, as `dancegen eval` reads `.npy`).
pub fn f64_values(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
    values(obj, what, |v| v)
}

/// An error unless every value is finite.
pub fn check_finite(what: &str, data: &[f32]) -> PyResult<()> {
    match data.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(fail(format!(
            "{what}: value {i} is {} (not a finite number)",
            data[i]
        ))),
    }
}
