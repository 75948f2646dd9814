//! `CameraAt.undistort_maps` and `CameraAt.undistort_image` (and `Calibration`'s, which
//! are those): numpy in and out over
//! etl-image's parallel undistortion (the GIL released while it runs).

use etl_core::model::{Distortion, Intrinsics};
use etl_image::undistort::{undistort_image, undistort_maps, OutputCamera, Sample, SourceImage};
use numpy::ndarray::{Array2, ArrayD, IxDyn};
use numpy::{Element, IntoPyArray, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::errors::{input_error, invalid, invalid_value, CoreResultExt};

/// What `image` must be, said once for every refusal.
const IMAGE_KINDS: &str = "image must be a numpy array of dtype uint8, uint16 or float32 of shape (h, w) or (h, w, 3)";

/// The output camera: `new_camera_matrix` (3 x 3, no skew, last row 0 0 1) or K(E), of
/// `size` (width, height) or `default_size`.
pub(crate) fn output_camera(
    k: &Intrinsics,
    new_camera_matrix: Option<&Bound<'_, PyAny>>,
    size: Option<&Bound<'_, PyAny>>,
    default_size: [u32; 2],
) -> PyResult<OutputCamera> {
    let (w, h) = match size {
        None => (default_size[0] as usize, default_size[1] as usize),
        Some(s) => {
            let (w, h): (i64, i64) =
                s.extract().map_err(|_| invalid("size", "size must be (width, height) in px, two integers"))?;
            if w < 0 || h < 0 {
                return Err(invalid_value("size", [w, h], format!("size ({w}, {h}) px must not be negative")));
            }
            (w as usize, h as usize)
        }
    };
    let Some(m) = new_camera_matrix else { return OutputCamera::of_intrinsics(k, w, h).py() };
    let m: [[f64; 3]; 3] = m
        .extract::<[[f64; 3]; 3]>()
        .or_else(|_| m.call_method0("tolist").and_then(|l| l.extract()))
        .map_err(|_| invalid("new_camera_matrix", "new_camera_matrix must be a 3 x 3 array of numbers"))?;
    if m[0][1] != 0.0 || m[1][0] != 0.0 || m[2] != [0.0, 0.0, 1.0] {
        return Err(invalid(
            "new_camera_matrix",
            "new_camera_matrix must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew); got another matrix",
        ));
    }
    OutputCamera::new(m[0][0], m[1][1], m[0][2], m[1][2], w, h).py()
}

/// The maps as two (h, w) float32 arrays.
pub(crate) fn maps_out<'py>(
    py: Python<'py>,
    k: &Intrinsics,
    d: &Distortion,
    out: &OutputCamera,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let maps = crate::pool::detach(py, || undistort_maps(k, d, out)).py()?;
    maps_arrays(py, maps)
}

/// `maps` as two (h, w) float32 arrays, for `cv2.remap`.
pub(crate) fn maps_arrays<'py>(
    py: Python<'py>,
    maps: etl_image::undistort::UndistortMaps,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let (w, h) = (maps.width_px(), maps.height_px());
    let (mx, my) = maps.into_parts();
    let shape = |v: Vec<f32>| Array2::from_shape_vec((h, w), v).map_err(|e| input_error(e.to_string()));
    Ok((shape(mx)?.into_pyarray(py).into_any(), shape(my)?.into_pyarray(py).into_any()))
}

/// The undistorted image of a numpy image of dtype T, same shape and dtype, or None when
/// `image` is not of dtype T.
fn try_dtype<'py, T: Sample + Element + Send + Sync>(
    image: &Bound<'py, PyAny>,
    k: &Intrinsics,
    d: &Distortion,
    image_size: [u32; 2],
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let Ok(a) = image.extract::<PyReadonlyArrayDyn<'py, T>>() else { return Ok(None) };
    let shape = a.shape().to_vec();
    let (h, w, c) = match shape.as_slice() {
        [h, w] => (*h, *w, 1),
        [h, w, 3] => (*h, *w, 3),
        _ => return Err(invalid_value("image", shape.as_slice(), format!("{IMAGE_KINDS}; got shape {shape:?}"))),
    };
    if [w as u64, h as u64] != [image_size[0] as u64, image_size[1] as u64] {
        return Err(invalid_value(
            "image",
            [w, h],
            format!("image is {w} x {h} px, the calibration is for {} x {} px", image_size[0], image_size[1]),
        ));
    }
    let out = OutputCamera::of_intrinsics(k, w, h).py()?;
    let py = image.py();
    // A C-ordered array is read in place; anything else is copied once, row-major.
    let owned: Vec<T>;
    let data: &[T] = match a.as_slice() {
        Ok(s) if a.is_c_contiguous() => s,
        _ => {
            owned = a.as_array().iter().copied().collect();
            &owned
        }
    };
    let zero = T::from_f32(0.0);
    let pixels = crate::pool::detach(py, || -> etl_image::Result<Vec<T>> {
        let src = SourceImage::new(data, w, h, c)?;
        undistort_image(k, d, &out, &src, zero)
    })
    .py()?;
    let arr = ArrayD::from_shape_vec(IxDyn(&shape), pixels).map_err(|e| input_error(e.to_string()))?;
    Ok(Some(arr.into_pyarray(py).into_any()))
}

/// `CameraAt.undistort_image` of the camera K `k` with distortion `d`: dispatch on the
/// dtype.
pub(crate) fn image_out<'py>(
    image: &Bound<'py, PyAny>,
    k: &Intrinsics,
    d: &Distortion,
    image_size: [u32; 2],
) -> PyResult<Bound<'py, PyAny>> {
    if let Some(r) = try_dtype::<u8>(image, k, d, image_size)? {
        return Ok(r);
    }
    if let Some(r) = try_dtype::<u16>(image, k, d, image_size)? {
        return Ok(r);
    }
    if let Some(r) = try_dtype::<f32>(image, k, d, image_size)? {
        return Ok(r);
    }
    let what = match image.getattr("dtype") {
        Ok(dt) => format!("dtype {dt}"),
        Err(_) => format!("a {}", image.get_type().name().map_or_else(|_| "?".to_owned(), |n| n.to_string())),
    };
    Err(invalid_value("image", &what, format!("{IMAGE_KINDS}; got {what}")))
}
