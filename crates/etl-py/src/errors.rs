//! The exception hierarchy of `etlcal` and the mapping of the Rust error types onto it.
//!
//! Every exception raised by the library derives from `etlcal.Error`; the message is the
//! Rust error's `Display` text, unchanged, so the CLI and Python say the same thing.
//!
//! | class | bases | raised for |
//! |---|---|---|
//! | `Error` | `Exception` | base of all below |
//! | `InputError` | `Error`, `ValueError` | bad input: NaN, out of range, too few, degenerate data, malformed files |
//! | `NotConvergedError` | `Error` | an iterative method missed its tolerance |
//! | `BoardNotFoundError` | `Error` | no checkerboard found in an image |
//! | `FileError` | `Error`, `OSError` | reading or writing a file failed |
//! | `DeviceError` | `Error` | the lens driver answered wrongly or not at all |
//! | `DeviceTimeoutError` | `DeviceError`, `TimeoutError` | the lens driver did not answer in time |
//!
//! The classes are made with `type(name, bases, namespace)` because two of them have two
//! bases (pyo3's `create_exception!` takes one).
//!
//! `InputError` has two attributes, `None` when absent: `what`, the flag, key, field or
//! argument to change (`"views[3].points"`, `"square_mm"`, `"search_ma"`), and `value`,
//! the offending value as text, numbers printed compactly (`"1e308"`, `"NaN"`). They come
//! from `etl_formats::Error::InvalidInput`'s fields and from etl-core's range and
//! finiteness checks (`OutOfRange`, `NotFinite`).

use etl_core::lens::LensErrorKind;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

/// The exception classes, created once per interpreter.
pub struct Exceptions {
    /// `etlcal.Error`.
    pub base: Py<PyType>,
    /// `etlcal.InputError`.
    pub input: Py<PyType>,
    /// `etlcal.NotConvergedError`.
    pub not_converged: Py<PyType>,
    /// `etlcal.BoardNotFoundError`.
    pub board_not_found: Py<PyType>,
    /// `etlcal.FileError`.
    pub file: Py<PyType>,
    /// `etlcal.DeviceError`.
    pub device: Py<PyType>,
    /// `etlcal.DeviceTimeoutError`.
    pub device_timeout: Py<PyType>,
}

static EXCEPTIONS: PyOnceLock<Exceptions> = PyOnceLock::new();

/// A class `name` of module `etlcal` with `bases`, `doc` and class attributes `attrs`
/// (their default for every instance).
fn make_type(
    py: Python<'_>,
    name: &str,
    bases: &[&Bound<'_, PyAny>],
    doc: &str,
    attrs: &[(&str, Py<PyAny>)],
) -> PyResult<Py<PyType>> {
    let ns = PyDict::new(py);
    ns.set_item("__module__", "etlcal")?;
    ns.set_item("__doc__", doc)?;
    for (key, value) in attrs {
        ns.set_item(key, value)?;
    }
    let bases = PyTuple::new(py, bases)?;
    let ty = py.get_type::<PyType>().call1((name, bases, ns))?;
    Ok(ty.cast_into::<PyType>()?.unbind())
}

fn build(py: Python<'_>) -> PyResult<Exceptions> {
    let builtins = py.import("builtins")?;
    let exception = builtins.getattr("Exception")?;
    let value_error = builtins.getattr("ValueError")?;
    let os_error = builtins.getattr("OSError")?;
    let timeout_error = builtins.getattr("TimeoutError")?;
    let base = make_type(py, "Error", &[&exception], "Base class of every exception raised by etlcal.", &[])?;
    let b = base.bind(py).as_any().clone();
    let input = make_type(
        py,
        "InputError",
        &[&b, &value_error],
        "Bad input: a NaN, a value out of range, too few points/views/currents, data that \
         do not determine the unknowns, a malformed file. Also a ValueError.\n\n\
         Attributes (None when the error names none): what -- the flag, file key, field or \
         argument to change (e.g. \"views[3].points\", \"square_mm\", \"search_ma\"); \
         value -- the offending value as text, numbers printed compactly (e.g. \"1e308\", \"NaN\").",
        &[("what", py.None()), ("value", py.None())],
    )?;
    let not_converged = make_type(
        py,
        "NotConvergedError",
        &[&b],
        "An iterative method (undistortion, Levenberg-Marquardt, autofocus, ...) did not \
         reach its tolerance.",
        &[],
    )?;
    let board_not_found =
        make_type(py, "BoardNotFoundError", &[&b], "No checkerboard (or only part of it) was found in an image.", &[])?;
    let file = make_type(py, "FileError", &[&b, &os_error], "Reading or writing a file failed. Also an OSError.", &[])?;
    let device = make_type(
        py,
        "DeviceError",
        &[&b],
        "The lens driver (a serial port or the virtual lens) failed or answered wrongly.",
        &[],
    )?;
    let d = device.bind(py).as_any().clone();
    let device_timeout = make_type(
        py,
        "DeviceTimeoutError",
        &[&d, &timeout_error],
        "The lens driver did not answer in time. Also a TimeoutError.",
        &[],
    )?;
    Ok(Exceptions { base, input, not_converged, board_not_found, file, device, device_timeout })
}

/// The exception classes of this interpreter.
pub fn exceptions(py: Python<'_>) -> PyResult<&Exceptions> {
    EXCEPTIONS.get_or_try_init(py, || build(py))
}

/// Which class a Rust error maps to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `InputError`.
    Input,
    /// `NotConvergedError`.
    NotConverged,
    /// `BoardNotFoundError`.
    BoardNotFound,
    /// `FileError`.
    File,
    /// `DeviceError`.
    Device,
    /// `DeviceTimeoutError`.
    DeviceTimeout,
}

/// A Python exception of class `kind` with message `msg`.
pub fn raise(kind: Kind, msg: impl Into<String>) -> PyErr {
    let msg: String = msg.into();
    Python::attach(|py| match exceptions(py) {
        Ok(ex) => {
            let ty = match kind {
                Kind::Input => &ex.input,
                Kind::NotConverged => &ex.not_converged,
                Kind::BoardNotFound => &ex.board_not_found,
                Kind::File => &ex.file,
                Kind::Device => &ex.device,
                Kind::DeviceTimeout => &ex.device_timeout,
            };
            PyErr::from_type(ty.bind(py).clone(), (msg,))
        }
        Err(e) => e,
    })
}

/// Bad input (an `InputError`, also a `ValueError`) raised by the bindings themselves,
/// e.g. an array of the wrong shape; `what` and `value` are `None`.
pub fn input_error(msg: impl Into<String>) -> PyErr {
    raise(Kind::Input, msg)
}

/// An `InputError` with message `msg` whose attributes `what` and `value` are set (`None`
/// for `None`): see the module doc.
pub fn input_error_about(msg: impl Into<String>, what: Option<&str>, value: Option<&str>) -> PyErr {
    let msg: String = msg.into();
    Python::attach(|py| {
        let make = || -> PyResult<PyErr> {
            let instance = exceptions(py)?.input.bind(py).call1((msg,))?;
            instance.setattr("what", what)?;
            instance.setattr("value", value)?;
            Ok(PyErr::from_value(instance))
        };
        make().unwrap_or_else(|e| e)
    })
}

/// An `InputError` about the argument or key `what` (its `what`), with no single
/// offending value (`value` None): a missing key, a wrong type, arguments that exclude
/// each other.
pub fn invalid(what: &str, msg: impl Into<String>) -> PyErr {
    input_error_about(msg, Some(what), None)
}

/// An `InputError` about the argument or key `what` whose offending `value` is kept as
/// text the way messages print it (`etl_formats::InputValue`: numbers compact).
pub fn invalid_value(what: &str, value: impl etl_formats::InputValue, msg: impl Into<String>) -> PyErr {
    input_error_about(msg, Some(what), Some(&value.to_input_value()))
}

/// The class of an etl-core error.
pub fn core_kind(e: &etl_core::Error) -> Kind {
    match e {
        etl_core::Error::NotConverged { .. } => Kind::NotConverged,
        _ => Kind::Input,
    }
}

/// An etl-core error as a Python exception (same message); a range or finiteness check
/// names its input and value (`etl_formats::Error::core_input`).
pub fn core_err(e: etl_core::Error) -> PyErr {
    match core_kind(&e) {
        Kind::Input => {
            let (what, value) = etl_formats::Error::core_input(&e);
            input_error_about(e.to_string(), what, value.as_deref())
        }
        kind => raise(kind, e.to_string()),
    }
}

/// The class of a lens error, from its kind: one mapping for every lens failure, whether
/// it comes straight from a `Lens` or through a library procedure.
pub fn lens_kind(kind: LensErrorKind) -> Kind {
    match kind {
        LensErrorKind::Timeout => Kind::DeviceTimeout,
        LensErrorKind::InvalidInput => Kind::Input,
        _ => Kind::Device,
    }
}

/// An error of the std library crates as a Python exception (same message), the class
/// from its kind.
pub fn calib_err(e: etl_formats::Error) -> PyErr {
    use etl_formats::ErrorKind as K;
    let kind = match (&e, e.kind()) {
        (etl_formats::Error::Core(c), _) => core_kind(c),
        (etl_formats::Error::Lens { kind, .. }, _) => lens_kind(*kind),
        (_, K::Io | K::Output) => Kind::File,
        (_, K::BoardNotFound) => Kind::BoardNotFound,
        _ => Kind::Input,
    };
    match kind {
        Kind::Input => input_error_about(e.to_string(), e.input_what(), e.input_value().as_deref()),
        _ => raise(kind, e.to_string()),
    }
}

/// `Result<T, etl_core::Error>` -> `PyResult<T>`.
pub trait CoreResultExt<T> {
    /// Maps the error with [`core_err`].
    fn py(self) -> PyResult<T>;
}

impl<T> CoreResultExt<T> for Result<T, etl_core::Error> {
    fn py(self) -> PyResult<T> {
        self.map_err(core_err)
    }
}

impl<T> CoreResultExt<T> for Result<T, etl_calib::Error> {
    fn py(self) -> PyResult<T> {
        self.map_err(calib_err)
    }
}

/// Adds the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let ex = exceptions(py)?;
    m.add("Error", ex.base.bind(py))?;
    m.add("InputError", ex.input.bind(py))?;
    m.add("NotConvergedError", ex.not_converged.bind(py))?;
    m.add("BoardNotFoundError", ex.board_not_found.bind(py))?;
    m.add("FileError", ex.file.bind(py))?;
    m.add("DeviceError", ex.device.bind(py))?;
    m.add("DeviceTimeoutError", ex.device_timeout.bind(py))?;
    Ok(())
}

/// Test hook: raises the exception a given Rust error maps to, so that pytest can check
/// every variant of the Rust error types (including those no public function can reach
/// from valid Python input, such as `BufferTooSmall`).
///
/// `kind` names the variant: `core:NotFinite`, `core:OutOfRange`, `core:TooFew`,
/// `core:Degenerate`, `core:BehindCamera`, `core:NotConverged`, `core:BufferTooSmall`,
/// `core:InvalidArgument`, `calib:Io`, `calib:Parse`, `calib:Format`, `calib:Image`,
/// `calib:BoardNotFound`, `calib:InvalidInput`, `calib:InvalidInputNoValue`, `calib:Core`,
/// `calib:LensTimeout`.
/// Returns the message the Rust side formats, after raising it.
#[pyfunction]
pub fn _raise_rust_error(kind: &str) -> PyResult<()> {
    use etl_core::Error as C;
    let core = |e: C| Err(core_err(e));
    let calib = |e: etl_calib::Error| Err(calib_err(e));
    let p = std::path::PathBuf::from("x.json");
    match kind {
        "core:NotFinite" => core(C::NotFinite { what: "x" }),
        "core:OutOfRange" => core(C::OutOfRange { what: "x", value: 5.0, min: 0.0, max: 1.0 }),
        "core:TooFew" => core(C::TooFew { what: "views", needed: 3, got: 1 }),
        "core:Degenerate" => core(C::Degenerate { what: "all points on one line" }),
        "core:BehindCamera" => core(C::BehindCamera),
        "core:NotConverged" => core(C::NotConverged { what: "solver", iterations: 7 }),
        "core:BufferTooSmall" => core(C::BufferTooSmall { what: "out", needed: 4, got: 2 }),
        "core:InvalidArgument" => core(C::InvalidArgument { what: "bad" }),
        "calib:Io" => calib(etl_calib::Error::Io {
            path: p,
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "not there"),
        }),
        "calib:Parse" => calib(etl_calib::Error::Parse { path: p, message: "line 1".into() }),
        "calib:Format" => calib(etl_calib::Error::Format { path: p, found: "a/1".into(), expected: "b/1".into() }),
        "calib:Image" => calib(etl_calib::Error::Image { path: p, message: "truncated".into() }),
        "calib:BoardNotFound" => calib(etl_calib::Error::BoardNotFound("img.png".into())),
        "calib:InvalidInput" => calib(etl_calib::Error::invalid_value("square_mm", -1.5, "negative")),
        "calib:InvalidInputNoValue" => calib(etl_calib::Error::invalid("views", "observations hold no views")),
        "calib:Core" => calib(etl_calib::Error::Core(C::NotConverged { what: "ba", iterations: 3 })),
        "calib:LensTimeout" => calib(etl_calib::Error::Lens {
            kind: LensErrorKind::Timeout,
            message: "no reply to GetTemperature within 500ms".into(),
        }),
        _ => Err(input_error(format!("unknown error kind {kind:?}"))),
    }
}

/// `f`, with a panic turned into `etlcal.Error` and a report file, as `etlcal._guard` turns
/// them for the functions, methods and properties it wraps. For what that Python wrapper
/// cannot reach: the constructors (CPython refuses a Python `__new__` over an extension
/// type's) and the special methods (a Python slot would slow every `len()` and `repr()`).
/// `qualname` is the call as the user wrote it (`Calibration.__repr__`).
pub fn guarded<T>(qualname: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    // Unwind safety: on a panic nothing `f` touched is used again but the error.
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f))
        .unwrap_or_else(|payload| Err(Python::attach(|py| panic_error(py, qualname, payload.as_ref()))))
}

/// [`guarded`] for a body that cannot fail but by panicking.
pub fn guarded_value<T>(qualname: &str, f: impl FnOnce() -> T) -> PyResult<T> {
    guarded(qualname, || Ok(f()))
}

/// The `etlcal.Error` a panic with `payload` in `qualname` becomes (`_guard._panic_error`
/// writes the report; if that module cannot be reached, the error says no report was written).
fn panic_error(py: Python<'_>, qualname: &str, payload: &(dyn std::any::Any + Send)) -> PyErr {
    let message = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".to_string());
    let panic = pyo3::panic::PanicException::new_err(message.clone()).into_value(py);
    let base = match exceptions(py) {
        Ok(ex) => ex.base.bind(py).clone(),
        Err(e) => return e,
    };
    let error = py
        .import("etlcal._guard")
        .and_then(|g| g.getattr("_panic_error")?.call1((qualname, panic, &base, env!("CARGO_PKG_VERSION"))));
    match error {
        Ok(e) => PyErr::from_value(e),
        Err(_) => PyErr::from_type(
            base,
            (format!("internal error in {qualname}: {message} (a bug in etlcal; no report written)"),),
        ),
    }
}

/// A test hook: panics with `message` (in a rayon worker when `in_pool`, as a parallel
/// call's bug would), so that the tests see what a bug at the binding boundary becomes
/// (`etlcal._guard`: `etlcal.Error` with a report file, never PanicException).
#[pyfunction]
#[pyo3(signature = (message, in_pool=false))]
pub fn _panic(py: Python<'_>, message: &str, in_pool: bool) -> PyResult<()> {
    if in_pool {
        crate::pool::detach(py, || {
            use rayon::prelude::*;
            (0..4).into_par_iter().for_each(|i| {
                if i == 3 {
                    panic!("{message}")
                }
            })
        });
    }
    panic!("{message}")
}

/// A test hook: a class whose method, static method and property panic (the kinds
/// `etlcal._guard` wraps), and whose constructor (on request), `repr` and `len` panic (the
/// kinds [`guarded`] covers).
#[pyclass(frozen, module = "etlcal")]
pub struct _PanicProbe {
    armed: bool,
}

#[pymethods]
impl _PanicProbe {
    #[new]
    fn new(panic_now: bool) -> PyResult<Self> {
        guarded_value("_PanicProbe.__new__", || {
            assert!(!panic_now, "the constructor panicked");
            _PanicProbe { armed: true }
        })
    }
    fn method(&self) {
        assert!(!self.armed, "the method panicked");
    }
    #[staticmethod]
    fn static_method() {
        panic!("the static method panicked")
    }
    #[getter]
    fn property(&self) -> bool {
        assert!(!self.armed, "the property panicked");
        false
    }
    fn __repr__(&self) -> PyResult<String> {
        guarded_value("_PanicProbe.__repr__", || {
            assert!(!self.armed, "the repr panicked");
            String::new()
        })
    }
    fn __len__(&self) -> PyResult<usize> {
        guarded_value("_PanicProbe.__len__", || {
            assert!(!self.armed, "the len panicked");
            0
        })
    }
}
