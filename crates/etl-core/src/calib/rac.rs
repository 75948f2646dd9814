//! The radial alignment constraint (RAC, Eq. 19-20): R, tx, ty and the aspect ratio from
//! all views together.
//!
//! All ETL views share one R and T (the world frame is the displacement stage), so the
//! points of all views form one non-coplanar 3D target and Tsai's non-coplanar method
//! applies. With centred pixels u, v (from the principal point of A0) and s = fx / fy,
//! u / v = s X_C / Y_C gives, per point, the linear equation (Eq. 20 with docs/METHOD.md's
//! erratum: the third entry is v Z_W)
//!
//! ```text
//! [v X, v Y, v Z, v, -u X, -u Y, -u Z] . L = u,   L = [s r1, s r2, s r3, s tx, r4, r5, r6] / ty
//! ```
//!
//! then |ty| = 1 / |L5..7|, s = |ty| |L1..3|, the sign of ty from the point farthest from
//! the centre (X_C must have the sign of u), r7..9 = r1..3 x r4..6, and R is replaced by
//! the nearest rotation. Distortion and the slight change of s with E are ignored: RAC is
//! an initialiser; bundle adjustment removes what it leaves.

use super::observations::{point_count, validate, View};
use crate::error::{Error, Result};
use crate::fit::GivensQr;
use crate::linalg::svd::Svd;
use crate::model::rotation::{matrix_to_rodrigues, nearest_rotation, Mat3};
use nalgebra::Vector3;

/// What RAC determines.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RacSolution {
    /// R (world -> camera) as a Rodrigues vector.
    pub rotation_rodrigues: [f64; 3],
    /// R as a matrix.
    pub rotation: Mat3,
    /// tx, mm.
    pub tx_mm: f64,
    /// ty, mm.
    pub ty_mm: f64,
    /// The aspect ratio s = fx / fy seen by the data.
    pub aspect: f64,
}

/// Solves Eq. 20 over every point of every view.
///
/// Preconditions (typed errors): at least 7 points; finite input; no empty view; the
/// points not all on one plane of constant Z_W and not all on the optical axis
/// ([`Error::Degenerate`]: RAC needs depth, i.e. views at several stage positions).
///
/// ```
/// use etl_core::calib::{rac::rac, Point, View};
/// use etl_core::model::CameraModel;
/// let cam = CameraModel::paper_rig();
/// let mut pts = [[Point { world_mm: [0.0; 3], pixel: [0.0; 2] }; 12]; 3];
/// for (k, (z, e)) in [(60.0, 90.0), (31.0, 130.0), (8.0, 200.0)].into_iter().enumerate() {
///     for i in 0..12 {
///         let w = [1.5 * (i % 4) as f64, 1.5 * (i / 4) as f64, z];
///         pts[k][i] = Point { world_mm: w, pixel: cam.project(w, e).unwrap() };
///     }
/// }
/// let views = [View { e_com_ma: 90.0, points: &pts[0] }, View { e_com_ma: 130.0, points: &pts[1] },
///              View { e_com_ma: 200.0, points: &pts[2] }];
/// let sol = rac(&views, cam.principal_point).unwrap();
/// assert!((sol.rotation_rodrigues[0] - 0.2).abs() < 0.01); // distortion makes it approximate
/// ```
pub fn rac(views: &[View<'_>], principal_point: [f64; 2]) -> Result<RacSolution> {
    validate(views)?;
    let n = point_count(views);
    if n < 7 {
        return Err(Error::TooFew { what: "points for RAC", needed: 7, got: n });
    }
    let [u0, v0] = principal_point;
    if !(u0.is_finite() && v0.is_finite()) {
        return Err(Error::NotFinite { what: "principal_point" });
    }
    // Scale world coordinates and pixels to O(1) for the conditioning of the solve.
    let (mut ws, mut ps) = (0.0f64, 0.0f64);
    for v in views {
        for p in v.points {
            ws = ws.max(p.world_mm[0].abs()).max(p.world_mm[1].abs()).max(p.world_mm[2].abs());
            ps = ps.max((p.pixel[0] - u0).abs()).max((p.pixel[1] - v0).abs());
        }
    }
    if !(ws > 0.0 && ps > 0.0) {
        return Err(Error::Degenerate { what: "all points at the world origin or at the principal point" });
    }
    let mut qr = GivensQr::<7>::full();
    for view in views {
        for p in view.points {
            let [x, y, z] = [p.world_mm[0] / ws, p.world_mm[1] / ws, p.world_mm[2] / ws];
            let (u, v) = ((p.pixel[0] - u0) / ps, (p.pixel[1] - v0) / ps);
            qr.add_row(&[v * x, v * y, v * z, v, -u * x, -u * y, -u * z], u, 1.0)?;
        }
    }
    // Rank check before solving: a plane of constant Z makes column 3 a multiple of 4.
    // The rank from etl-core's one-sided Jacobi SVD, accurate to high relative precision.
    if Svd::of_rows(qr.r_factor()).rank(1e-9) < 7 {
        return Err(Error::Degenerate {
            what: "RAC needs depth: the points lie on one plane (views at several stage positions Z_W are needed)",
        });
    }
    let l = qr.solve()?;
    // Undo the scaling: L1..3 and L5..7 multiply world coordinates (in units of ws).
    let l13 = Vector3::new(l[0], l[1], l[2]) / ws;
    let l4 = l[3];
    let l57 = Vector3::new(l[4], l[5], l[6]) / ws;
    let (n57, n13) = (l57.norm(), l13.norm());
    if !(n57 > 0.0 && n13 > 0.0) {
        return Err(Error::Degenerate { what: "RAC solution has a zero row of R" });
    }
    let mut ty = 1.0 / n57;
    let s = ty * n13;
    // Sign of ty: the point farthest from the centre must have X_C with the sign of u
    // and Y_C with the sign of v.
    let mut best = (0.0, [0.0; 3], [0.0; 2]);
    for view in views {
        for p in view.points {
            let (u, v) = (p.pixel[0] - u0, p.pixel[1] - v0);
            let d = u * u + v * v;
            if d > best.0 {
                best = (d, p.world_mm, [u, v]);
            }
        }
    }
    let (w, uv) = (Vector3::from(best.1), best.2);
    let xc = (l13.dot(&w) + l4) * ty / s;
    let yc = (l57.dot(&w) + 1.0) * ty;
    if xc * uv[0] + yc * uv[1] < 0.0 {
        ty = -ty;
    }
    let r1 = l13 * ty / s;
    let r2 = l57 * ty;
    let tx = l4 * ty / s;
    // R's rows are r1, r2, r1 x r2.
    let rot = nearest_rotation(&[r1.into(), r2.into(), r1.cross(&r2).into()]);
    Ok(RacSolution { rotation_rodrigues: matrix_to_rodrigues(&rot), rotation: rot, tx_mm: tx, ty_mm: ty, aspect: s })
}
