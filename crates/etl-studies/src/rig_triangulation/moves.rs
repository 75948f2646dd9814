//! The 2 mm move of a trial: the rig's board at stage position Z and at Z + 2 mm, every
//! corner both cameras see at both positions triangulated by the estimated rig, the move
//! measured as the length of the corners' mean displacement; beside it, camera 0's PnP of
//! the same pixels.
//!
//! Two cases: the cameras refocus on the board at each position (each at the current its
//! focus law gives, [`focus_current_ma`]: the settings change with the move, as an
//! autofocusing system's do), or keep the settings of the first position. The points of
//! the two positions are compared in camera 0's frame at E = 0 (X + s_0 e_z, s_0 its
//! centre's move, [`centre_shift_mm`]): with a moving centre, camera 0's frame at its
//! setting moves when the setting does.

use etl_calib::rig::{CalibrationPart, Rig};
use etl_core::model::CameraModel;
use etl_core::pnp::displacement_mm;
use etl_core::runtime::rig::centre_shift_mm;
use etl_formats::{Error, Result, Trust};
use etl_sim::multi_camera::{corner_mm, focus_current_ma, MULTI_CAMERA_BOARD};
use rand_chacha::ChaCha8Rng;

use super::{gauss, in_image, settings_of};

/// The length of the move, mm.
pub const MOVE_MM: f64 = 2.0;

/// The fewest corners both cameras must see at both positions.
pub const MIN_COMMON_CORNERS: usize = 12;

/// Every board corner's pixel in each camera, None where it does not see it.
pub type BoardPixels = Vec<[Option<[f64; 2]>; 2]>;

/// Measured minus true length of the move, um, by each measurement.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MoveErrors {
    /// Triangulated, the cameras refocused at each position.
    pub triangulated_refocused_um: f64,
    /// Triangulated, the settings of the first position kept.
    pub triangulated_fixed_um: f64,
    /// Camera 0's PnP, refocused.
    pub pnp_refocused_um: f64,
    /// Camera 0's PnP, settings kept.
    pub pnp_fixed_um: f64,
    /// The corners triangulated (refocused case).
    pub corners: usize,
}

/// Every board corner's noisy pixel in each true camera at stage position `z_mm` and
/// currents `e_com_ma` (None where outside the image).
fn observe(truths: &[CameraModel], z_mm: f64, e_com_ma: [f64; 2], sigma_px: f64, rng: &mut ChaCha8Rng) -> BoardPixels {
    let [cols, rows] = MULTI_CAMERA_BOARD.inner_corners;
    (0..cols * rows)
        .map(|i| {
            let [x, y] = corner_mm(i);
            std::array::from_fn(|k| {
                let p = truths[k].project([x, y, z_mm], e_com_ma[k]).ok().filter(|p| in_image(*p))?;
                Some([p[0] + gauss(sigma_px, rng), p[1] + gauss(sigma_px, rng)])
            })
        })
        .collect()
}

/// The mean over `corners` of the points triangulated from `obs` at `e_com_ma`, in camera
/// 0's frame at E = 0 (module docs).
fn mean_point(
    rig: &Rig,
    (e_com_ma, temperature_c): ([f64; 2], f64),
    obs: &[[Option<[f64; 2]>; 2]],
    corners: &[usize],
    sigma_px: f64,
) -> Result<[f64; 3]> {
    let at = rig.at(&settings_of(&e_com_ma, temperature_c)?, &[temperature_c; 2], Trust::Refuse)?;
    let c0 = &at.cameras()[0];
    let s0 = centre_shift_mm(c0.model(), c0.setting_value(), 0.0);
    let mut sum = [0.0; 3];
    for &i in corners {
        let t = at.triangulate(&obs[i], sigma_px, CalibrationPart::PixelOnly)?;
        let p = t.point_mm;
        for (s, x) in sum.iter_mut().zip([p[0], p[1], p[2] + s0]) {
            *s += x;
        }
    }
    Ok(sum.map(|s| s / corners.len() as f64))
}

/// Camera 0's PnP of the move: the board's origin at both positions by [`solve_pnp`]
/// (`etl_core`'s `CameraAt::solve_pnp`, every corner camera 0 sees, board corner i at
/// `corners_mm[i]`), the length of its displacement.
///
/// [`solve_pnp`]: etl_core::runtime::CameraAt::solve_pnp
fn pnp_move_mm(
    rig: &Rig,
    (temperature_c, corners_mm): (f64, &[[f64; 2]]),
    [(ea, obs_a), (eb, obs_b)]: [([f64; 2], &BoardPixels); 2],
) -> Result<f64> {
    let pose = |e: [f64; 2], obs: &[[Option<[f64; 2]>; 2]]| -> Result<_> {
        let at = rig.at(&settings_of(&e, temperature_c)?, &[temperature_c; 2], Trust::Refuse)?;
        let (board, px): (Vec<[f64; 3]>, Vec<[f64; 2]>) =
            obs.iter().zip(corners_mm).filter_map(|(o, c)| o[0].map(|p| ([c[0], c[1], 0.0], p))).unzip();
        Ok(at.cameras()[0].solve_pnp(&board, &px)?)
    };
    let d = displacement_mm(&pose(ea, obs_a)?, &pose(eb, obs_b)?);
    Ok(d.iter().map(|x| x * x).sum::<f64>().sqrt())
}

/// The move between two records of the board (module docs), the first at stage position
/// Z with settings `ea`, the second at Z + [`MOVE_MM`] with `eb`; board corner i at
/// `corners_mm[i]`: the triangulated and camera 0's PnP length minus [`MOVE_MM`], um,
/// and the corners both cameras see at both positions (at least [`MIN_COMMON_CORNERS`],
/// else refused, `corners`).
pub fn measure_move(
    rig: &Rig,
    (temperature_c, corners_mm): (f64, &[[f64; 2]]),
    [(ea, a), (eb, b)]: [([f64; 2], &BoardPixels); 2],
    sigma_px: f64,
) -> Result<(f64, f64, usize)> {
    let both = |o: &[Option<[f64; 2]>; 2]| o.iter().all(Option::is_some);
    let corners: Vec<usize> = (0..a.len()).filter(|&i| both(&a[i]) && both(&b[i])).collect();
    if corners.len() < MIN_COMMON_CORNERS {
        return Err(Error::invalid(
            "corners",
            format!(
                "corners: {} seen by both cameras at both positions, fewer than {MIN_COMMON_CORNERS}",
                corners.len()
            ),
        ));
    }
    let pa = mean_point(rig, (ea, temperature_c), a, &corners, sigma_px)?;
    let pb = mean_point(rig, (eb, temperature_c), b, &corners, sigma_px)?;
    let tri = (0..3).map(|i| (pb[i] - pa[i]).powi(2)).sum::<f64>().sqrt();
    let pnp = pnp_move_mm(rig, (temperature_c, corners_mm), [(ea, a), (eb, b)])?;
    Ok((1000.0 * (tri - MOVE_MM), 1000.0 * (pnp - MOVE_MM), corners.len()))
}

/// One case of the move: the triangulated and the PnP length minus [`MOVE_MM`], um, and
/// the corners used.
fn one_case(
    (rig, truths, temperature_c): (&Rig, &[CameraModel], f64),
    z_mm: f64,
    [ea, eb]: [[f64; 2]; 2],
    sigma_px: f64,
    rng: &mut ChaCha8Rng,
) -> Result<(f64, f64, usize)> {
    let a = observe(truths, z_mm, ea, sigma_px, rng);
    let b = observe(truths, z_mm + MOVE_MM, eb, sigma_px, rng);
    let [cols, rows] = MULTI_CAMERA_BOARD.inner_corners;
    let corners_mm: Vec<[f64; 2]> = (0..cols * rows).map(corner_mm).collect();
    measure_move(rig, (temperature_c, &corners_mm), [(ea, &a), (eb, &b)], sigma_px)
}

/// The move from stage position `z_mm` (module docs), the estimated `rig` against the
/// simulation's `truths`, pixel noise `sigma_px`, at `temperature_c`.
pub fn move_errors(
    rig: &Rig,
    truths: &[CameraModel],
    temperature_c: f64,
    z_mm: f64,
    sigma_px: f64,
    rng: &mut ChaCha8Rng,
) -> Result<MoveErrors> {
    let focus = |z: f64| -> [f64; 2] { std::array::from_fn(|k| focus_current_ma(&truths[k], &truths[0], (k, 2), z)) };
    let (first, second) = (focus(z_mm), focus(z_mm + MOVE_MM));
    let context = (rig, truths, temperature_c);
    let (tri_r, pnp_r, corners) = one_case(context, z_mm, [first, second], sigma_px, rng)?;
    let (tri_f, pnp_f, _) = one_case(context, z_mm, [first, first], sigma_px, rng)?;
    Ok(MoveErrors {
        triangulated_refocused_um: tri_r,
        triangulated_fixed_um: tri_f,
        pnp_refocused_um: pnp_r,
        pnp_fixed_um: pnp_f,
        corners,
    })
}
