//! [`undistort_maps`]: for every pixel of the undistorted image, where it is in the
//! distorted one.

mod opencv;

use core::ops::Range;

use super::pinhole::OutputCamera;
use crate::error::{all_finite, Error, Result};
use crate::model::{Distortion, DistortionModel, Intrinsics};

/// Fills the undistortion maps of the output rows `rows` (a band of the output image) in
/// `cv2.remap`'s convention: `map_x[i]`, `map_y[i]` (`i = (y - rows.start) * width + x`)
/// is the pixel of the distorted image (model intrinsics `k`, distortion `d` at one
/// current) that the output pixel (x, y) of the camera `out` sees.
///
/// The output pixel's ray is ((x - cx) / fx', (y - cy) / fy', 1) (fx', fy', cx', cy' of
/// `out`); the model projects it (Eq. 15, 17) to
///
/// ```text
/// u = fx (x - cx') / fx',  v = fy (y - cy') / fy',  (u_d, v_d) = distort(u, v),
/// map_x = u_d + u0,  map_y = v_d + v0
/// ```
///
/// evaluated in f64 (along a row by Horner's rule, see `row_polynomials`; for the opencv
/// family OpenCV's distortion of the ray's normalised point, u_d = fx x_d(x', y') with
/// x' = (x - cx') / fx') and rounded once to f32: every entry is the model's own projection of
/// that ray to within f32 rounding (6e-8 relative, 1.2e-4 px at 2000 px). With the default
/// output camera ([`OutputCamera::of_intrinsics`]) u = x - u0, v = y - v0.
///
/// Preconditions: `rows.start <= rows.end <= out.height_px`; `map_x`, `map_y` hold at
/// least `rows.len() * out.width_px` elements (the rest is left as it is).
///
/// Errors: an invalid `out` (as [`OutputCamera::validate`]); `k` with a focal length that
/// is not finite and positive or a non-finite principal point, `d` not finite
/// ([`Error::InvalidArgument`] / [`Error::NotFinite`]); rows beyond the image
/// ([`Error::OutOfRange`]); a buffer too short ([`Error::BufferTooSmall`] naming it).
/// On error nothing is written.
// Inlined into its callers, so that one running it under a wider instruction set (the
// runtime dispatch of etl-image's undistortion: AVX2, AVX-512) compiles this loop for it.
#[inline(always)]
pub fn undistort_maps(
    k: &Intrinsics,
    d: &Distortion,
    out: &OutputCamera,
    rows: Range<usize>,
    map_x: &mut [f32],
    map_y: &mut [f32],
) -> Result<()> {
    out.validate()?;
    check_model(k, d)?;
    check_band(out, &rows, map_x.len(), map_y.len())?;
    if d.model() == DistortionModel::OpenCv {
        for_each_row(out.width_px, rows, map_x, map_y, &opencv::OpenCvRow::new(k, d, out));
    } else {
        for_each_row(out.width_px, rows, map_x, map_y, &PaperRow::new(k, d, out));
    }
    Ok(())
}

/// The maps of one output row of a distortion family: `fill(y, row_x, row_y)` writes row
/// `y`'s entries of each map. A trait of structs rather than closures, so that each
/// family's loop is `#[inline(always)]` into [`undistort_maps`] and compiled for its
/// caller's instruction set (etl-image's runtime dispatch).
pub(super) trait FillRow {
    /// Writes the maps of output row `y` into `row_x`, `row_y` (one entry per pixel).
    fn fill(&self, y: usize, row_x: &mut [f32], row_y: &mut [f32]);
}

/// Runs `rows.fill` on each output row `y` of the band `rows` with that row's `width`
/// entries of each map: the walk over a band both families' maps share.
#[inline(always)]
fn for_each_row(width: usize, band: Range<usize>, map_x: &mut [f32], map_y: &mut [f32], rows: &impl FillRow) {
    for (i, y) in band.enumerate() {
        // The band was checked to fit: `get_mut` keeps it a checked fact, not a panic path.
        let span = i * width..(i + 1) * width;
        let (Some(row_x), Some(row_y)) = (map_x.get_mut(span.clone()), map_y.get_mut(span)) else { break };
        rows.fill(y, row_x, row_y);
    }
}

/// The paper family's rows (Eq. 17 by [`row_polynomials`]): along a row u = a x + b is
/// affine in x and v constant, one multiply-add per pixel.
struct PaperRow<'a> {
    k: &'a Intrinsics,
    d: &'a Distortion,
    /// (a, b) of u = a x + b and of v = a y + b.
    u_of_x: (f64, f64),
    v_of_y: (f64, f64),
}

impl<'a> PaperRow<'a> {
    #[inline(always)]
    fn new(k: &'a Intrinsics, d: &'a Distortion, out: &OutputCamera) -> Self {
        let u_of_x = (k.fx / out.fx_px, -k.fx * out.cx_px / out.fx_px);
        let v_of_y = (k.fy / out.fy_px, -k.fy * out.cy_px / out.fy_px);
        PaperRow { k, d, u_of_x, v_of_y }
    }
}

impl FillRow for PaperRow<'_> {
    #[inline(always)]
    fn fill(&self, y: usize, row_x: &mut [f32], row_y: &mut [f32]) {
        let ((ax, bx), (ay, by)) = (self.u_of_x, self.v_of_y);
        let [cx, cy] = row_polynomials(self.d, ay * y as f64 + by, self.k.u0, self.k.v0);
        for (x, (mx, my)) in row_x.iter_mut().zip(row_y.iter_mut()).enumerate() {
            let u = ax * x as f64 + bx;
            *mx = (cx[0] + u * (cx[1] + u * (cx[2] + u * cx[3]))) as f32;
            *my = (cy[0] + u * (cy[1] + u * cy[2])) as f32;
        }
    }
}

/// Eq. 17 along a row: at fixed v, u_d + u0 is a cubic and v_d + v0 a quadratic in u,
///
/// ```text
/// u_d + u0 = (p1 v^2 + u0) + (1 + k1 v^2 + 2 p2 v) u + 3 p1 u^2 + k1 u^3
/// v_d + v0 = (v + k1 v^3 + 3 p2 v^2 + v0) + 2 p1 v u + (k1 v + p2) u^2
/// ```
///
/// (expanding k1 u r^2 + p1 (3u^2 + v^2) + 2 p2 u v and k1 v r^2 + 2 p1 u v +
/// p2 (u^2 + 3v^2)): five multiply-adds per pixel by Horner's rule instead of about twenty,
/// the same numbers to f64 rounding. Returns the coefficients, lowest degree first.
#[inline]
fn row_polynomials(d: &Distortion, v: f64, u0: f64, v0: f64) -> [[f64; 4]; 2] {
    let [k1, p1, p2, ..] = *d.padded();
    let vv = v * v;
    [
        [p1 * vv + u0, 1.0 + k1 * vv + 2.0 * p2 * v, 3.0 * p1, k1],
        [v + k1 * vv * v + 3.0 * p2 * vv + v0, 2.0 * p1 * v, k1 * v + p2, 0.0],
    ]
}

/// The model at one current must be usable: its fields are public, so it is checked here.
pub(crate) fn check_model(k: &Intrinsics, d: &Distortion) -> Result<()> {
    if !(k.fx > 0.0 && k.fy > 0.0 && k.fx.is_finite() && k.fy.is_finite()) {
        return Err(Error::InvalidArgument { what: "model intrinsics: fx and fy must be finite and > 0" });
    }
    all_finite(&[k.u0, k.v0], "model principal point")?;
    all_finite(d.coefficients(), "distortion coefficients")
}

/// Checks a band of output rows against the image and the buffers.
pub(crate) fn check_band(out: &OutputCamera, rows: &Range<usize>, len_x: usize, len_y: usize) -> Result<()> {
    if rows.start > rows.end || rows.end > out.height_px {
        return Err(Error::OutOfRange {
            what: "band of rows (end)",
            value: rows.end as f64,
            min: rows.start as f64,
            max: out.height_px as f64,
        });
    }
    // At most 2^20 rows of 2^20 pixels: no overflow.
    let needed = (rows.end - rows.start) * out.width_px;
    if len_x < needed {
        return Err(Error::BufferTooSmall { what: "map_x", needed, got: len_x });
    }
    if len_y < needed {
        return Err(Error::BufferTooSmall { what: "map_y", needed, got: len_y });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::projection::project_camera_point;
    use crate::model::CameraModel;

    const W: usize = 1936;
    const H: usize = 1458;

    /// Every entry of the maps over the whole paper-rig image, at three currents, against
    /// the model's own projection of that output pixel's ray (a camera point on it).
    #[test]
    fn maps_are_the_models_projection_of_each_ray_whole_image() {
        let cam = CameraModel::paper_rig();
        let mut map_x = [0.0f32; W + 64];
        let mut map_y = [0.0f32; W + 64];
        for e in [80.0, 150.0, 225.0] {
            let (k, d) = (cam.intrinsics(e).unwrap(), cam.distortion(e).unwrap());
            // The default camera and a new one (zoomed out, shifted, another size).
            let cams = [
                OutputCamera::of_intrinsics(&k, W, H).unwrap(),
                OutputCamera::new(0.8 * k.fx, 0.82 * k.fy, 1000.0, 700.0, W + 64, H - 58).unwrap(),
            ];
            for out in cams {
                let mut worst = 0.0f64;
                for y in 0..out.height_px {
                    undistort_maps(&k, &d, &out, y..y + 1, &mut map_x, &mut map_y).unwrap();
                    for x in 0..out.width_px {
                        // The ray through (x, y) of `out`, scaled to a depth of 500 mm.
                        let z = 500.0;
                        let pc = [z * (x as f64 - out.cx_px) / out.fx_px, z * (y as f64 - out.cy_px) / out.fy_px, z];
                        let p = project_camera_point(pc, &k, &d).unwrap();
                        let err = (map_x[x] as f64 - p[0]).abs().max((map_y[x] as f64 - p[1]).abs());
                        worst = worst.max(err);
                    }
                }
                assert!(worst < 1e-3, "E = {e}: worst {worst} px");
                // f32 rounding is the only error: half an ulp at ~2000 px is 6.1e-5.
                assert!(worst < 2.5e-4, "E = {e}: worst {worst} px");
            }
        }
    }

    #[test]
    fn bands_give_the_same_maps_as_one_pass() {
        let cam = CameraModel::paper_rig();
        let (k, d) = (cam.intrinsics(120.0).unwrap(), cam.distortion(120.0).unwrap());
        let out = OutputCamera::of_intrinsics(&k, 40, 30).unwrap();
        let (mut ax, mut ay) = ([0.0f32; 1200], [0.0f32; 1200]);
        undistort_maps(&k, &d, &out, 0..30, &mut ax, &mut ay).unwrap();
        let (mut bx, mut by) = ([0.0f32; 1200], [0.0f32; 1200]);
        for r in [0..7, 7..8, 8..8, 8..30] {
            let (s, e) = (r.start * 40, r.end * 40);
            undistort_maps(&k, &d, &out, r, &mut bx[s..e], &mut by[s..e]).unwrap();
        }
        assert_eq!(ax, bx);
        assert_eq!(ay, by);
        // The default camera: the centre of the image maps onto the principal point's
        // neighbourhood only through distortion, which is 0 at (u0, v0).
        let out = OutputCamera::of_intrinsics(&k, 1000, 600).unwrap();
        let (mut rx, mut ry) = ([0.0f32; 1000], [0.0f32; 1000]);
        undistort_maps(&k, &d, &out, 550..551, &mut rx, &mut ry).unwrap();
        assert_eq!((rx[900], ry[900]), (900.0, 550.0));
    }

    #[test]
    fn bad_inputs_are_named_errors_and_write_nothing() {
        let cam = CameraModel::paper_rig();
        let (k, d) = (cam.intrinsics(120.0).unwrap(), cam.distortion(120.0).unwrap());
        let out = OutputCamera::of_intrinsics(&k, 10, 4).unwrap();
        let (mut mx, mut my) = ([7.0f32; 40], [7.0f32; 39]);
        let e = undistort_maps(&k, &d, &out, 0..4, &mut mx, &mut my).unwrap_err();
        assert_eq!(e, Error::BufferTooSmall { what: "map_y", needed: 40, got: 39 });
        let e = undistort_maps(&k, &d, &out, 0..4, &mut mx[..30], &mut my).unwrap_err();
        assert_eq!(e, Error::BufferTooSmall { what: "map_x", needed: 40, got: 30 });
        let e = undistort_maps(&k, &d, &out, 2..5, &mut mx, &mut my).unwrap_err();
        assert!(matches!(e, Error::OutOfRange { what: "band of rows (end)", .. }), "{e:?}");
        let zero = OutputCamera { width_px: 0, ..out };
        let e = undistort_maps(&k, &d, &zero, 0..1, &mut mx, &mut my).unwrap_err();
        assert!(matches!(e, Error::OutOfRange { what: "output width_px", .. }), "{e:?}");
        let bad_k = Intrinsics { fx: -1.0, ..k };
        let e = undistort_maps(&bad_k, &d, &out, 0..1, &mut mx, &mut my).unwrap_err();
        assert!(matches!(e, Error::InvalidArgument { .. }), "{e:?}");
        let [_, p1, p2, ..] = *d.padded();
        let bad_d = Distortion::paper(f64::NAN, p1, p2);
        let e = undistort_maps(&k, &bad_d, &out, 0..1, &mut mx, &mut my).unwrap_err();
        assert_eq!(e, Error::NotFinite { what: "distortion coefficients" });
        assert!(mx.iter().chain(my.iter()).all(|&v| v == 7.0), "nothing written on error");
    }
}
