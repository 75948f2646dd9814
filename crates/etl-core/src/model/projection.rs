//! [`CameraModel`]: the parameters of an ETL camera and the projection (Eq. 13-18), world
//! point to observed pixel, with its intrinsics at a current ([`Intrinsics`]) and the
//! pixel-level undistortion ([`CameraModel::undistort`]).
//!
//! Named `projection` for what it computes: the model's whole chain from world to pixel
//! (the module [`crate::runtime`] holds the calibrated camera at run time, and
//! [`crate::undistort`] the undistortion of whole images).

use serde::{Deserialize, Serialize};

use super::centre::MovingCentre;
use super::distortion::Distortion;
use super::family::{DistortionA, DistortionModel};
use super::focal::FocalPoly;
use nalgebra::Vector3;

use super::rotation::{rodrigues_to_matrix, to_matrix3, Mat3};
use crate::error::{all_finite, finite, Error, Result};

/// The numbers of the ETL camera model: the paper's 25 (Eq. 13-18: pose, cubic focal
/// polynomials, principal point, a1..a9) or, generalised, a focal polynomial of any degree
/// 1..=5 and either distortion family ([`DistortionModel`]). The parameter vector of a
/// model is laid out by [`super::params::Layout`] ([`Self::layout`]).
///
/// Invariants a *usable* model satisfies (checked where they matter, never assumed):
/// all numbers finite; kf_x and kf_y of one degree; fx(E), fy(E) > 0 over the currents it
/// is used at. Field names are those of the `etlcal.calibration/1` file format.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraModel {
    /// Rodrigues vector of R (world -> camera), radians.
    pub rotation_rodrigues: [f64; 3],
    /// T (world -> camera), mm.
    pub translation_mm: [f64; 3],
    /// `fx(E) = kf_x[0] + kf_x[1] E + ... + kf_x[d] E^d` (px; E in mA), Eq. 16 (the paper: d = 3).
    pub kf_x: FocalPoly,
    /// fy(E), as `kf_x` (same degree).
    pub kf_y: FocalPoly,
    /// (u0, v0), px.
    pub principal_point: [f64; 2],
    /// The a_i of Eq. 18 (the paper: a1..a9) with their distortion family.
    pub distortion_a: DistortionA,
    /// The projection centre's and the principal point's move with E (Eq. C1-C3), or
    /// `None` for the paper's fixed centre.
    pub centre: Option<MovingCentre>,
}

/// As the fields of `etlcal.calibration/1` (what `etlcal simulate` writes as the truth):
/// the paper's model exactly as before the families (kf of 4, distortion_a of 9), other
/// layouts with their lengths and, for the opencv family, `"distortion_model": "opencv"`
/// before `distortion_a`.
impl Serialize for CameraModel {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> core::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let family = self.distortion_model();
        let named = family != DistortionModel::Paper;
        let fields = 6 + usize::from(named) + usize::from(self.centre.is_some());
        let mut st = serializer.serialize_struct("CameraModel", fields)?;
        st.serialize_field("rotation_rodrigues", &self.rotation_rodrigues)?;
        st.serialize_field("translation_mm", &self.translation_mm)?;
        st.serialize_field("kf_x", &self.kf_x)?;
        st.serialize_field("kf_y", &self.kf_y)?;
        st.serialize_field("principal_point", &self.principal_point)?;
        if named {
            st.serialize_field("distortion_model", &family)?;
        }
        st.serialize_field("distortion_a", &self.distortion_a)?;
        if let Some(c) = &self.centre {
            st.serialize_field("centre", &CentreFields::of(c, self.principal_point))?;
        }
        st.end()
    }
}

/// The file's `"centre"`: each polynomial's ascending coefficients in E from E^0, dz's
/// constant 0 (Eq. C1) and the principal point's the model's (u0, v0).
#[derive(Serialize)]
struct CentreFields {
    dz_mm: [f64; 3],
    principal_point_px: [[f64; 2]; 2],
}

impl CentreFields {
    fn of(c: &MovingCentre, principal_point: [f64; 2]) -> Self {
        let [u1, v1] = c.principal_point_slope_px;
        CentreFields {
            dz_mm: [0.0, c.dz_mm[0], c.dz_mm[1]],
            principal_point_px: [[principal_point[0], u1], [principal_point[1], v1]],
        }
    }
}

/// Pinhole intrinsics at one current.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Focal length along u, px.
    pub fx: f64,
    /// Focal length along v, px.
    pub fy: f64,
    /// Principal point u0, px.
    pub u0: f64,
    /// Principal point v0, px.
    pub v0: f64,
}

impl Intrinsics {
    /// The 3 x 3 matrix A of Eq. 15, row-major.
    pub fn matrix(&self) -> Mat3 {
        [[self.fx, 0.0, self.u0], [0.0, self.fy, self.v0], [0.0, 0.0, 1.0]]
    }
}

impl CameraModel {
    /// The simulated rig of the paper's section 5.1.2 (docs/METHOD.md, "The paper rig").
    pub const fn paper_rig() -> Self {
        CameraModel {
            rotation_rodrigues: [0.2, 0.2, 0.2],
            translation_mm: [-11.0, -4.0, 48.0],
            kf_x: FocalPoly::cubic([5380.0, -7.0, 0.02, -3e-5]),
            kf_y: FocalPoly::cubic([5430.0, -7.0, 0.02, -3e-5]),
            principal_point: [900.0, 550.0],
            distortion_a: DistortionA::paper([
                -0.067, -5.19e-5, 1.09e-8, -0.0077, 0.103, -1.93e-5, 0.11, -0.0257, 5.6e-6,
            ]),
            centre: None,
        }
    }

    /// The distortion family of the model.
    pub const fn distortion_model(&self) -> DistortionModel {
        self.distortion_a.model()
    }

    /// The degree of the focal polynomials (kf_x's; [`Self::validate`] checks kf_y's).
    pub const fn focal_degree(&self) -> usize {
        self.kf_x.degree()
    }

    /// Image size of the paper rig's camera, px (width, height).
    pub const PAPER_IMAGE_SIZE: [u32; 2] = [1936, 1458];

    /// A camera with strong barrel distortion in OpenCV's family: a short prime (about
    /// 6 mm, fx 1375..1247 px over 80..225 mA) behind the ETL on the paper rig's sensor
    /// ([`Self::PAPER_IMAGE_SIZE`]), with k1 = -0.28..-0.32, k2 = 0.14..0.16,
    /// k3 = -0.019..-0.021 (normalised units) and small decentering (p1 ~ 2e-4, p2 =
    /// -3e-4), all varying with focus through w = 1 / f_mean (Eq. 18):
    ///
    /// ```text
    /// k1 = -0.3 - 540 (w - w0) + 2e5 (w - w0)^2,  k2 = 0.15 + 270 (w - w0),
    /// p1 = 2e-4 + 0.5 (w - w0),  p2 = -3e-4,  k3 = -0.02 - 20 (w - w0),  w0 = 7.6e-4 / px
    /// ```
    ///
    /// The distortion is one-to-one over the whole image at every current of 80..225 mA.
    /// The pose puts the world origin (a stage's) about 200 mm in front of the camera.
    /// The simulated strong-distortion rig and the tests of the opencv family use it.
    pub const fn strong_distortion_rig() -> Self {
        CameraModel {
            rotation_rodrigues: [0.05, -0.08, 0.02],
            translation_mm: [-60.0, -45.0, 200.0],
            kf_x: FocalPoly::cubic([1500.0, -1.96, 0.0056, -8.4e-6]),
            kf_y: FocalPoly::cubic([1510.0, -1.96, 0.0056, -8.4e-6]),
            principal_point: [980.0, 720.0],
            distortion_a: DistortionA::opencv([
                2.0e5, -844.0, 0.22592, // k1
                0.0, 270.0, -0.0552, // k2
                0.0, 0.5, -1.8e-4, // p1
                0.0, 0.0, -3.0e-4, // p2
                0.0, -20.0, -4.8e-3, // k3
            ]),
            centre: None,
        }
    }

    /// Checks that every number of the model is finite.
    pub fn validate(&self) -> Result<()> {
        all_finite(&self.rotation_rodrigues, "rotation_rodrigues")?;
        all_finite(&self.translation_mm, "translation_mm")?;
        self.kf_x.validate("kf_x")?;
        self.kf_y.validate("kf_y")?;
        if self.kf_x.degree() != self.kf_y.degree() {
            return Err(Error::InvalidArgument { what: "kf_x and kf_y must have the same degree" });
        }
        all_finite(&self.principal_point, "principal_point")?;
        if let Some(c) = &self.centre {
            c.validate()?;
        }
        self.distortion_a.validate()
    }

    /// The principal point (u0, v0) at `e_com_ma` (Eq. C3; the fixed one without a moving
    /// centre), px.
    #[inline]
    pub fn principal_point_at(&self, e_com_ma: f64) -> [f64; 2] {
        let [u0, v0] = self.principal_point;
        match &self.centre {
            None => [u0, v0],
            Some(c) => {
                let [du, dv] = c.principal_point_shift_px(e_com_ma);
                [u0 + du, v0 + dv]
            }
        }
    }

    /// T at `e_com_ma` (Eq. C2: the translation of the centre there; `translation_mm` for
    /// the fixed centre), mm.
    #[inline]
    pub fn translation_at(&self, e_com_ma: f64) -> [f64; 3] {
        let [tx, ty, tz] = self.translation_mm;
        let dz = self.centre.as_ref().map_or(0.0, |c| c.dz_mm_at(e_com_ma));
        [tx, ty, tz - dz]
    }

    /// Rotation matrix R (world -> camera).
    #[inline]
    pub fn rotation_matrix(&self) -> Mat3 {
        rodrigues_to_matrix(self.rotation_rodrigues)
    }

    /// Focal lengths (fx, fy) in px at compensated current `e_com_ma` (Eq. 16), unchecked.
    #[inline]
    pub fn focal_lengths(&self, e_com_ma: f64) -> (f64, f64) {
        (self.kf_x.eval(e_com_ma), self.kf_y.eval(e_com_ma))
    }

    /// Intrinsics at compensated current `e_com_ma` (Eq. 16).
    ///
    /// Errors: a non-finite current; a focal length that is not positive there (the cubic
    /// is used far outside its range).
    pub fn intrinsics(&self, e_com_ma: f64) -> Result<Intrinsics> {
        finite(e_com_ma, "e_com_ma")?;
        let (fx, fy) = self.focal_lengths(e_com_ma);
        let [u0, v0] = self.principal_point_at(e_com_ma);
        if !(fx > 0.0 && fy > 0.0 && fx.is_finite() && fy.is_finite()) {
            return Err(Error::Degenerate { what: "focal length is not positive at this current" });
        }
        if !(u0.is_finite() && v0.is_finite()) {
            return Err(Error::NotFinite { what: "principal_point" });
        }
        Ok(Intrinsics { fx, fy, u0, v0 })
    }

    /// The distortion at compensated current `e_com_ma` (Eq. 18): k1, p1, p2 (paper) or
    /// k1, k2, p1, p2, k3 (opencv).
    ///
    /// Errors: as [`Self::intrinsics`]; non-finite coefficients (NaN or infinite a_i, or
    /// an overflow) ([`Error::NotFinite`]).
    pub fn distortion(&self, e_com_ma: f64) -> Result<Distortion> {
        let k = self.intrinsics(e_com_ma)?;
        let d = Distortion::from_a(&self.distortion_a, k.fx, k.fy);
        all_finite(d.coefficients(), "distortion coefficients (check distortion_a)")?;
        Ok(d)
    }

    /// World point (mm) -> camera coordinates (mm), Eq. 13, with the centre of the
    /// calibration's pose (for a moving centre, the centre at E = 0: use
    /// [`Self::world_to_camera_at`] at a setting).
    #[inline]
    pub fn world_to_camera(&self, world_mm: [f64; 3]) -> [f64; 3] {
        (to_matrix3(&self.rotation_matrix()) * Vector3::from(world_mm) + Vector3::from(self.translation_mm)).into()
    }

    /// World point (mm) -> camera coordinates (mm) at `e_com_ma`: Eq. 13 with T(E) of
    /// Eq. C2 (the centre where the lens puts it).
    #[inline]
    pub fn world_to_camera_at(&self, world_mm: [f64; 3], e_com_ma: f64) -> [f64; 3] {
        let t = Vector3::from(self.translation_at(e_com_ma));
        (to_matrix3(&self.rotation_matrix()) * Vector3::from(world_mm) + t).into()
    }

    /// Projects a world point (mm) to the observed pixel at compensated current `e_com_ma`
    /// (Eq. 13-18).
    ///
    /// Errors: non-finite input; the point at or behind the camera; a non-positive focal
    /// length at that current.
    pub fn project(&self, world_mm: [f64; 3], e_com_ma: f64) -> Result<[f64; 2]> {
        all_finite(&world_mm, "world_mm")?;
        let k = self.intrinsics(e_com_ma)?;
        let d = Distortion::from_a(&self.distortion_a, k.fx, k.fy);
        let pc = self.world_to_camera_at(world_mm, e_com_ma);
        project_camera_point(pc, &k, &d)
    }

    /// Projects many world points at one current into `out` (same length as `world_mm`).
    ///
    /// The intrinsics, distortion and rotation are computed once. On error `out` holds the
    /// points before the failing one.
    pub fn project_many(&self, world_mm: &[[f64; 3]], e_com_ma: f64, out: &mut [[f64; 2]]) -> Result<()> {
        if out.len() < world_mm.len() {
            return Err(Error::BufferTooSmall { what: "out", needed: world_mm.len(), got: out.len() });
        }
        let k = self.intrinsics(e_com_ma)?;
        let d = Distortion::from_a(&self.distortion_a, k.fx, k.fy);
        let r = to_matrix3(&self.rotation_matrix());
        let t = Vector3::from(self.translation_at(e_com_ma));
        for (w, o) in world_mm.iter().zip(out.iter_mut()) {
            all_finite(w, "world_mm")?;
            *o = project_camera_point((r * Vector3::from(*w) + t).into(), &k, &d)?;
        }
        Ok(())
    }
}

/// Camera point (mm) -> observed pixel under intrinsics `k` and distortion `d`
/// (Eq. 15, 17; for the opencv family exactly `cv2.projectPoints`' expressions, `d`'s own
/// focal lengths unused).
#[inline]
pub fn project_camera_point(pc: [f64; 3], k: &Intrinsics, d: &Distortion) -> Result<[f64; 2]> {
    if !(pc[2] > 0.0) {
        return Err(Error::BehindCamera);
    }
    let px = match d.model() {
        DistortionModel::Paper => {
            let u = k.fx * pc[0] / pc[2];
            let v = k.fy * pc[1] / pc[2];
            let [ud, vd] = d.distort(u, v);
            [ud + k.u0, vd + k.v0]
        }
        // OpenCV's own order of operations (`cv2.projectPoints`): x = X / Z, then distort.
        DistortionModel::OpenCv => {
            let [xd, yd] = d.distort_normalised(pc[0] / pc[2], pc[1] / pc[2]);
            [k.fx * xd + k.u0, k.fy * yd + k.v0]
        }
    };
    if px[0].is_finite() && px[1].is_finite() {
        Ok(px)
    } else {
        Err(Error::NotFinite { what: "projected pixel" })
    }
}

impl CameraModel {
    /// Observed pixel -> the pixel it would have without distortion, in the same image
    /// frame: (u0 + u, v0 + v), where (u, v) solves Eq. 17 for the observed offsets.
    ///
    /// Accurate to 1e-9 px wherever it returns `Ok`; errors as [`Distortion::undistort`].
    pub fn undistort(&self, pixel: [f64; 2], e_com_ma: f64) -> Result<[f64; 2]> {
        all_finite(&pixel, "pixel")?;
        let k = self.intrinsics(e_com_ma)?;
        let d = Distortion::from_a(&self.distortion_a, k.fx, k.fy);
        let [u, v] = d.undistort(pixel[0] - k.u0, pixel[1] - k.v0)?;
        Ok([u + k.u0, v + k.v0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One point of the paper rig, computed by hand (each step written out).
    #[test]
    fn paper_rig_point_by_hand() {
        let cam = CameraModel::paper_rig();
        // Corner (i, j) = (4, 6) of the board at Z_W = 48 mm: X_W = 6.0, Y_W = 9.0.
        let pw = [6.0, 9.0, 48.0];
        let e = 100.0;
        // Rodrigues om = (0.2, 0.2, 0.2): t = sqrt(0.12) = 0.346410161513775,
        // a = sin t / t = 0.980119657713663, b = (1 - cos t) / t^2 = 0.495019957199948.
        let t = 0.12f64.sqrt();
        let a = t.sin() / t;
        let b = (1.0 - t.cos()) / 0.12;
        assert!((a - 0.980119657713663).abs() < 1e-14 && (b - 0.495019957199948).abs() < 1e-12);
        // R = I + a [om]x + b (om om^T - t^2 I): diagonal 1 + b (0.04 - 0.12),
        // off-diagonal b 0.04 -+ a 0.2.
        let d = 1.0 + b * (0.04 - 0.12);
        let p = b * 0.04 + a * 0.2;
        let m = b * 0.04 - a * 0.2;
        let r = [[d, m, p], [p, d, m], [m, p, d]];
        let pc = [
            r[0][0] * 6.0 + r[0][1] * 9.0 + r[0][2] * 48.0 - 11.0,
            r[1][0] * 6.0 + r[1][1] * 9.0 + r[1][2] * 48.0 - 4.0,
            r[2][0] * 6.0 + r[2][1] * 9.0 + r[2][2] * 48.0 + 48.0,
        ];
        // fx = 5380 - 700 + 200 - 30 = 4850, fy = 5430 - 700 + 200 - 30 = 4900.
        let (fx, fy) = (4850.0, 4900.0);
        let u = fx * pc[0] / pc[2];
        let v = fy * pc[1] / pc[2];
        // w = 1 / 4875.
        let w = 1.0 / 4875.0;
        let k1 = -0.067 * w * w - 5.19e-5 * w + 1.09e-8;
        let p1 = -0.0077 * w * w + 0.103 * w - 1.93e-5;
        let p2 = 0.11 * w * w - 0.0257 * w + 5.6e-6;
        let r2 = u * u + v * v;
        let ud = u + k1 * u * r2 + p1 * (3.0 * u * u + v * v) + 2.0 * p2 * u * v;
        let vd = v + k1 * v * r2 + 2.0 * p1 * u * v + p2 * (u * u + 3.0 * v * v);
        let expect = [ud + 900.0, vd + 550.0];
        let got = cam.project(pw, e).unwrap();
        assert!((got[0] - expect[0]).abs() < 1e-9 && (got[1] - expect[1]).abs() < 1e-9, "{got:?} {expect:?}");
        // And it is inside the image.
        assert!(got[0] > 0.0 && got[0] < 1935.0 && got[1] > 0.0 && got[1] < 1457.0);
    }

    #[test]
    fn behind_camera_and_nan_are_errors() {
        let cam = CameraModel::paper_rig();
        assert_eq!(cam.project([0.0, 0.0, -1000.0], 100.0), Err(Error::BehindCamera));
        assert!(matches!(cam.project([f64::NAN, 0.0, 0.0], 100.0), Err(Error::NotFinite { .. })));
        assert!(matches!(cam.project([0.0, 0.0, 10.0], f64::INFINITY), Err(Error::NotFinite { .. })));
        // fx(E) of the paper's cubic turns negative far above its range.
        assert!(matches!(cam.intrinsics(2000.0), Err(Error::Degenerate { .. })));
    }

    #[test]
    fn round_trip_dense_grid_whole_image() {
        let cam = CameraModel::paper_rig();
        for &e in &[0.0, 80.0, 225.0] {
            let k = cam.intrinsics(e).unwrap();
            let d = cam.distortion(e).unwrap();
            let mut worst = 0.0f64;
            // Ideal pixels on a dense grid over (a margin around) the image.
            for iy in 0..=73 {
                for ix in 0..=97 {
                    let (px, py) = (-20.0 + ix as f64 * 20.0, -20.0 + iy as f64 * 20.0);
                    let [ud, vd] = d.distort(px - k.u0, py - k.v0);
                    let back = cam.undistort([ud + k.u0, vd + k.v0], e).unwrap();
                    worst = worst.max((back[0] - px).abs()).max((back[1] - py).abs());
                }
            }
            assert!(worst < 1e-6, "E = {e}: worst round trip {worst} px");
        }
    }
}
