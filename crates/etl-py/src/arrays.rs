//! numpy in and out: (N, k) point arrays, 3 x 3 matrices, scalars-or-arrays.

use numpy::ndarray::{Array1, Array2, ArrayD, IxDyn};
use numpy::{
    AllowTypeChange, IntoPyArray, PyArrayDyn, PyArrayLikeDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyFloat;

use crate::errors::{input_error, invalid};

/// The most numbers an array argument may hold (2^26: 64 M numbers, 512 MiB as float64,
/// far above any rig's points or any grid of currents). Checked on the array's shape before
/// numpy converts it or etlcal copies it, so that a broadcast view of 2^31 rows (no memory
/// of its own) is refused in one line instead of aborting the interpreter when copied.
pub const MAX_ARRAY_NUMBERS: usize = 1 << 26;

/// Refuses a numpy array `obj` with more than `max` elements (the product of its shape),
/// naming `what`. Anything that is not an ndarray passes: a list's size is paid for already.
pub fn refuse_oversized(obj: &Bound<'_, PyAny>, what: &str, max: usize) -> PyResult<()> {
    let Ok(arr) = obj.cast::<PyUntypedArray>() else { return Ok(()) };
    let shape = arr.shape();
    match shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d)) {
        Some(n) if n <= max => Ok(()),
        n => {
            let n = n.map_or_else(|| "more than 2^64".to_owned(), |n| n.to_string());
            Err(invalid(
                what,
                format!("{what} has {n} elements (shape {shape:?}), more than the {max} an array argument may hold"),
            ))
        }
    }
}

/// The array argument `obj` (named `what`) as an ndarray of real numbers, to read from:
/// `obj` itself when it is one, else numpy's conversion of it (a list or tuple, converted
/// once here and read from the result). Refused: more than `max` elements
/// ([`refuse_oversized`]), and dtypes other than numpy's integer and float kinds (`i`, `u`,
/// `f`): bool, complex (numpy's cast would drop the imaginary part with only a warning),
/// strings (it would parse `"1.5"`), objects, dates.
pub fn real_array<'py>(obj: &Bound<'py, PyAny>, what: &str, max: usize) -> PyResult<Bound<'py, PyAny>> {
    refuse_oversized(obj, what, max)?;
    let arr = match obj.cast::<PyUntypedArray>() {
        Ok(a) => a.clone(),
        Err(_) => obj
            .py()
            .import("numpy")?
            .call_method1("asarray", (obj,))
            .and_then(|a| Ok(a.cast_into::<PyUntypedArray>()?))
            .map_err(|e| invalid(what, format!("{what} must be a number or an array of numbers: {e}")))?,
    };
    let dtype = arr.dtype();
    let kind: char = dtype.getattr("kind")?.extract()?;
    if !matches!(kind, 'i' | 'u' | 'f') {
        return Err(invalid(what, format!("{what} must hold real numbers (integer or float), got dtype {dtype}")));
    }
    Ok(arr.into_any())
}

/// Points of dimension `K` read from an array-like of shape (N, K) or (K,).
pub struct Points<const K: usize> {
    /// The points, in order.
    pub points: Vec<[f64; K]>,
    /// The input was one point of shape (K,): the result is one point too.
    pub single: bool,
}

/// Reads (N, K) or (K,) floats (any numeric dtype, any layout; lists too). `what` and
/// `unit` name the argument in the error message.
pub fn points<const K: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Points<K>> {
    let obj = real_array(obj, what, MAX_ARRAY_NUMBERS)?;
    let arr: PyArrayLikeDyn<'_, f64, AllowTypeChange> = obj
        .extract()
        .map_err(|e| invalid(what, format!("{what} must be an array of numbers of shape (N, {K}): {e}")))?;
    let shape = arr.shape().to_vec();
    let single = match shape.as_slice() {
        [k] if *k == K => true,
        [_, k] if *k == K => false,
        _ => return Err(invalid(what, format!("{what} must have shape (N, {K}) or ({K},), got {shape:?}"))),
    };
    // `as_slice` also accepts Fortran-ordered memory: only a C-ordered slice is row-major.
    let c_slice = if arr.is_c_contiguous() { arr.as_slice().ok() } else { None };
    let points = match c_slice {
        Some(flat) => flat.chunks_exact(K).map(|c| core::array::from_fn(|i| c[i])).collect(),
        None => {
            let view = arr.as_array();
            let n = if single { 1 } else { shape[0] };
            let view = view.to_shape((n, K)).map_err(|e| invalid(what, format!("{what}: {e}")))?;
            view.rows().into_iter().map(|r| core::array::from_fn(|i| r[i])).collect()
        }
    };
    Ok(Points { points, single })
}

/// Sets up rust-numpy's lazy state now (at import): its first use in a process imports
/// `numpy.lib` to read numpy's version, publishes the borrow-checking capsule and creates
/// the type that owns arrays handed to numpy, 0.15-0.2 ms that the first `detect_corners`
/// (or any first call taking an array) paid otherwise. numpy is imported anyway (by
/// `etlcal.results`). A failure is left for that first call to report.
pub fn prepare(py: Python<'_>) {
    if let Ok(a) = points_out(py, vec![[0.0f64; 2]], false) {
        let _ = a.extract::<numpy::PyReadonlyArray2<'_, f64>>();
    }
}

/// (N, K) float64 array from points (or (K,) when `single`).
pub fn points_out<'py, const K: usize>(
    py: Python<'py>,
    pts: Vec<[f64; K]>,
    single: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let n = pts.len();
    let flat: Vec<f64> = pts.into_iter().flatten().collect();
    if single {
        Ok(Array1::from(flat).into_pyarray(py).into_any())
    } else {
        let a = Array2::from_shape_vec((n, K), flat).map_err(|e| input_error(e.to_string()))?;
        Ok(a.into_pyarray(py).into_any())
    }
}

/// A 3 x 3 float64 array from a row-major matrix.
pub fn mat3_out<'py>(py: Python<'py>, m: [[f64; 3]; 3]) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = m.into_iter().flatten().collect();
    // 9 elements always fit a 3 x 3 shape.
    match Array2::from_shape_vec((3, 3), flat) {
        Ok(a) => a.into_pyarray(py).into_any(),
        Err(_) => py.None().into_bound(py),
    }
}

/// An R x C float64 array from a row-major matrix.
pub fn matrix_out<'py, const R: usize, const C: usize>(py: Python<'py>, m: &[[f64; C]; R]) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = m.iter().flatten().copied().collect();
    // R C elements always fit an R x C shape.
    match Array2::from_shape_vec((R, C), flat) {
        Ok(a) => a.into_pyarray(py).into_any(),
        Err(_) => py.None().into_bound(py),
    }
}

/// An n x n float64 array of `rows` (None if a row is not n long).
pub fn square_out<'py>(py: Python<'py>, rows: &[Vec<f64>]) -> Option<Bound<'py, PyAny>> {
    let n = rows.len();
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Array2::from_shape_vec((n, n), flat).ok().map(|a| a.into_pyarray(py).into_any())
}

/// A 1-D float64 array.
pub fn vec_out<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyAny> {
    Array1::from(v.to_vec()).into_pyarray(py).into_any()
}

/// Reads exactly `N` numbers (a sequence or 1-D array).
pub fn fixed<const N: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; N]> {
    let obj = real_array(obj, what, N)?;
    let arr: PyArrayLikeDyn<'_, f64, AllowTypeChange> =
        obj.extract().map_err(|e| invalid(what, format!("{what} must be {N} numbers: {e}")))?;
    if arr.len() != N || arr.ndim() != 1 {
        return Err(invalid(what, format!("{what} must be {N} numbers, got shape {:?}", arr.shape())));
    }
    let v = arr.as_array();
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(v.iter()) {
        *o = *x;
    }
    Ok(out)
}

/// Applies `f` to a float (-> float) or elementwise to an array-like (-> float64 array of
/// the same shape). Stops at the first error.
pub fn map1<'py>(x: &Bound<'py, PyAny>, what: &str, f: impl Fn(f64) -> PyResult<f64>) -> PyResult<Bound<'py, PyAny>> {
    let py = x.py();
    if let Ok(v) = x.cast::<PyFloat>() {
        return Ok(PyFloat::new(py, f(v.value())?).into_any());
    }
    if !x.hasattr("__len__")? && !x.hasattr("__array__")? {
        let v: f64 = x.extract().map_err(|e| invalid(what, format!("{what} must be a number or an array: {e}")))?;
        return Ok(PyFloat::new(py, f(v)?).into_any());
    }
    let x = real_array(x, what, MAX_ARRAY_NUMBERS)?;
    let arr: PyArrayLikeDyn<'_, f64, AllowTypeChange> =
        x.extract().map_err(|e| invalid(what, format!("{what} must be a number or an array: {e}")))?;
    if arr.ndim() == 0 {
        let v = *arr.as_array().iter().next().unwrap_or(&f64::NAN);
        return Ok(PyFloat::new(py, f(v)?).into_any());
    }
    let out = arr.as_array().mapv(|_| 0.0);
    let mut out = out;
    for (o, v) in out.iter_mut().zip(arr.as_array().iter()) {
        *o = f(*v)?;
    }
    Ok(out.into_pyarray(py).into_any())
}

/// Two arguments read as numbers, or as float64 arrays broadcast against each other
/// (numpy's rules).
pub enum Broadcast2 {
    /// Both were numbers (floats, integers; not 0-d arrays or sequences).
    Scalar(f64, f64),
    /// At least one was an array-like: the broadcast shape and both operands in
    /// row-major order over it.
    Array {
        /// The broadcast shape (empty for two 0-d arrays).
        shape: Vec<usize>,
        /// The first operand, broadcast.
        x: Vec<f64>,
        /// The second operand, broadcast.
        y: Vec<f64>,
    },
}

/// Reads two number-or-array arguments (`what` names them in errors) and broadcasts them.
pub fn broadcast2<'py>(a: &Bound<'py, PyAny>, b: &Bound<'py, PyAny>, what: (&str, &str)) -> PyResult<Broadcast2> {
    let py = a.py();
    let scalar = |x: &Bound<'py, PyAny>| -> PyResult<bool> {
        Ok(x.cast::<PyFloat>().is_ok() || (!x.hasattr("__len__")? && !x.hasattr("__array__")?))
    };
    if scalar(a)? && scalar(b)? {
        let x: f64 =
            a.extract().map_err(|e| invalid(what.0, format!("{} must be a number or an array: {e}", what.0)))?;
        let y: f64 =
            b.extract().map_err(|e| invalid(what.1, format!("{} must be a number or an array: {e}", what.1)))?;
        return Ok(Broadcast2::Scalar(x, y));
    }
    let np = py.import("numpy")?;
    let asf = |x: &Bound<'py, PyAny>, name: &str| -> PyResult<Bound<'py, PyAny>> {
        np.call_method1("asarray", (x, "float64"))
            .map_err(|e| invalid(name, format!("{name} must be a number or an array: {e}")))
    };
    let (a, b) = (real_array(a, what.0, MAX_ARRAY_NUMBERS)?, real_array(b, what.1, MAX_ARRAY_NUMBERS)?);
    let (a, b) = (asf(&a, what.0)?, asf(&b, what.1)?);
    let pair = np
        .call_method1("broadcast_arrays", (a, b))
        .map_err(|e| invalid(what.1, format!("{} and {} do not broadcast together: {e}", what.0, what.1)))?;
    let x: Bound<'py, PyArrayDyn<f64>> = pair.get_item(0)?.cast_into()?;
    let y: Bound<'py, PyArrayDyn<f64>> = pair.get_item(1)?.cast_into()?;
    // Broadcasting makes views: the result is costed before it is copied.
    refuse_oversized(x.as_any(), what.0, MAX_ARRAY_NUMBERS)?;
    let (x, y) = (x.readonly(), y.readonly());
    let shape = x.shape().to_vec();
    Ok(Broadcast2::Array {
        shape,
        x: x.as_array().iter().copied().collect(),
        y: y.as_array().iter().copied().collect(),
    })
}

/// Applies `f` to two floats, or elementwise to two array-likes broadcast against each
/// other (numpy's rules): a float for two numbers or two 0-d arrays, else a float64 array
/// of the broadcast shape. Stops at the first error.
pub fn map2<'py>(
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    what: (&str, &str),
    f: impl Fn(f64, f64) -> PyResult<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let py = a.py();
    match broadcast2(a, b, what)? {
        Broadcast2::Scalar(x, y) => Ok(PyFloat::new(py, f(x, y)?).into_any()),
        Broadcast2::Array { shape, x, y } => {
            let out = x.iter().zip(&y).map(|(u, v)| f(*u, *v)).collect::<PyResult<Vec<f64>>>()?;
            if shape.is_empty() {
                return Ok(PyFloat::new(py, out.first().copied().unwrap_or(f64::NAN)).into_any());
            }
            stacked(py, &shape, &[], out)
        }
    }
}

/// Currents given to a per-current model function: a number (the function's scalar
/// result) or an array of any shape S (every part of the result stacked on leading axes S).
pub enum Currents {
    /// A float, an integer or a 0-d array.
    Scalar(f64),
    /// An array-like of at least one dimension: its shape and its values, row-major.
    Array {
        /// The array's shape S.
        shape: Vec<usize>,
        /// Its values in row-major order.
        values: Vec<f64>,
    },
}

/// Reads a current argument (`what` names it in the error) as a scalar or an array.
pub fn currents(x: &Bound<'_, PyAny>, what: &str) -> PyResult<Currents> {
    if let Ok(v) = x.cast::<PyFloat>() {
        return Ok(Currents::Scalar(v.value()));
    }
    if !x.hasattr("__len__")? && !x.hasattr("__array__")? {
        let v: f64 = x.extract().map_err(|e| invalid(what, format!("{what} must be a number or an array: {e}")))?;
        return Ok(Currents::Scalar(v));
    }
    let x = real_array(x, what, MAX_ARRAY_NUMBERS)?;
    let arr: PyArrayLikeDyn<'_, f64, AllowTypeChange> =
        x.extract().map_err(|e| invalid(what, format!("{what} must be a number or an array of numbers: {e}")))?;
    let values: Vec<f64> = arr.as_array().iter().copied().collect();
    if arr.ndim() == 0 {
        return Ok(Currents::Scalar(values.first().copied().unwrap_or(f64::NAN)));
    }
    Ok(Currents::Array { shape: arr.shape().to_vec(), values })
}

/// A float64 array of shape `shape` followed by `inner`, from row-major `values`.
pub fn stacked<'py>(
    py: Python<'py>,
    shape: &[usize],
    inner: &[usize],
    values: Vec<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let full: Vec<usize> = shape.iter().chain(inner).copied().collect();
    let a = ArrayD::from_shape_vec(IxDyn(&full), values).map_err(|e| input_error(e.to_string()))?;
    Ok(a.into_pyarray(py).into_any())
}

/// The parts of a per-current function as Python values: part p is a float when the
/// current was a scalar and the part of shape () (`part_shapes[p]` empty), else a float64
/// array of shape `shape` + `part_shapes[p]` from the row-major `blocks[p]` (`shape` is
/// that of the array of currents; empty for a scalar).
pub fn parts_out<'py, const P: usize>(
    py: Python<'py>,
    shape: &[usize],
    scalar: bool,
    blocks: [Vec<f64>; P],
    part_shapes: [&[usize]; P],
) -> PyResult<[Bound<'py, PyAny>; P]> {
    let mut out = Vec::with_capacity(P);
    for (block, inner) in blocks.into_iter().zip(part_shapes) {
        out.push(match (scalar, inner.is_empty()) {
            (true, true) => PyFloat::new(py, block.first().copied().unwrap_or(f64::NAN)).into_any(),
            _ => stacked(py, shape, inner, block)?,
        });
    }
    out.try_into().map_err(|_| input_error("parts_out: part count mismatch"))
}
