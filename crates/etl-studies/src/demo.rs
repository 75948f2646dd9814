//! The demo's validation (`etlcal demo`): errors users feel of a calibration of the
//! simulated paper rig against its truth, on fresh views not used in the calibration.

use etl_core::model::CameraModel;
use etl_core::pnp::{displacement_mm, solve_pnp};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use etl_calib::pipeline::CalibrationResult;
use etl_formats::{Error, Result};
use etl_sim::simulate::{focused_z_mm, observe_board};

use crate::common::curve_errors;

/// Currents of the validation measurements, mA.
pub const VALIDATION_E_MA: [f64; 5] = [80.0, 120.0, 150.0, 190.0, 225.0];

/// Errors users feel, for one calibrated model.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Validation {
    /// Max relative error of fx(E) over the calibrated range.
    pub fx_curve_max_rel_err: f64,
    /// Max relative error of fy(E) over the calibrated range.
    pub fy_curve_max_rel_err: f64,
    /// Distance of the principal point from the truth, px.
    pub principal_point_err_px: f64,
    /// RMS reprojection error of the calibration, px.
    pub rms_reprojection_px: f64,
    /// PnP error of a 2 mm stage move, per current.
    pub pnp_displacement_err_um: Vec<serde_json::Value>,
}

/// Validates `result` against `truth` with fresh PnP measurements (same seed for every
/// model, so estimators are compared on the same views). With `images`, each measurement
/// renders the board before and after the move and detects its corners; otherwise the
/// corners are simulated with the paper's noise model.
pub fn validate(result: &CalibrationResult, truth: &CameraModel, seed: u64, images: bool) -> Result<Validation> {
    let m = result.calibration.model();
    let (ex, ey) = curve_errors(&m, truth, result.calibration.e_com_range_ma);
    let pp = (m.principal_point[0] - truth.principal_point[0]).hypot(m.principal_point[1] - truth.principal_point[1]);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5e_ed0f_9a11);
    let noise = etl_sim::simulate::NoiseModel::PAPER;
    let mut pnp = vec![];
    for (k, e) in VALIDATION_E_MA.into_iter().enumerate() {
        let z = focused_z_mm(e);
        let (a, b) = if images {
            rendered_move(truth, e, z, seed.wrapping_mul(7919).wrapping_add(k as u64))?
        } else {
            (observe_board(truth, z, e, &noise, &mut rng), observe_board(truth, z + 2.0, e, &noise, &mut rng))
        };
        let pose = |obs: &[([f64; 2], [f64; 2])]| {
            let board: Vec<[f64; 3]> = obs.iter().map(|(w, _)| [w[0], w[1], 0.0]).collect();
            let px: Vec<[f64; 2]> = obs.iter().map(|(_, p)| *p).collect();
            solve_pnp(&m, e, &board, &px)
        };
        let d = displacement_mm(&pose(&a)?, &pose(&b)?);
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        pnp.push(json!({"e_com_ma": e, "err_um": 1000.0 * (len - 2.0).abs()}));
    }
    Ok(Validation {
        fx_curve_max_rel_err: ex,
        fy_curve_max_rel_err: ey,
        principal_point_err_px: pp,
        rms_reprojection_px: result.calibration.rms_reprojection_px,
        pnp_displacement_err_um: pnp,
    })
}

/// (board X, Y in mm; detected pixel) of each corner of one view.
type BoardPixelPairs = Vec<([f64; 2], [f64; 2])>;

/// The board at stage positions `z_mm` and `z_mm + 2` at current `e_ma`, rendered and
/// detected: (board X, Y; detected pixel) of the block of corners visible in both.
fn rendered_move(truth: &CameraModel, e_ma: f64, z_mm: f64, seed: u64) -> Result<(BoardPixelPairs, BoardPixelPairs)> {
    use etl_sim::render::{render, Optics, RenderOptions, Scene};
    use etl_sim::simulate::images::{visible_block, ImageOptions};
    let (inner_corners, square_mm) = etl_sim::simulate::PAPER_BOARD;
    let board = etl_formats::dataset::Board { inner_corners, square_mm };
    let size = CameraModel::PAPER_IMAGE_SIZE;
    let options = ImageOptions::default();
    let blocks: Vec<_> = [z_mm, z_mm + 2.0]
        .iter()
        .map(|&z| visible_block(truth, e_ma, board, z, size, options.margin_px))
        .collect::<Option<Vec<_>>>()
        .ok_or_else(|| Error::InvalidInput(format!("validation at {e_ma} mA: the board does not fit the image")))?;
    // The block visible at both positions.
    let i0 = blocks[0].1[0].max(blocks[1].1[0]);
    let j0 = blocks[0].1[1].max(blocks[1].1[1]);
    let i1 = (blocks[0].1[0] + blocks[0].0.inner_corners[0]).min(blocks[1].1[0] + blocks[1].0.inner_corners[0]);
    let j1 = (blocks[0].1[1] + blocks[0].0.inner_corners[1]).min(blocks[1].1[1] + blocks[1].0.inner_corners[1]);
    let block =
        etl_formats::dataset::Board { inner_corners: [i1.saturating_sub(i0), j1.saturating_sub(j0)], square_mm };
    let first = [i0, j0];
    let mut out = vec![];
    for (n, z) in [z_mm, z_mm + 2.0].into_iter().enumerate() {
        let scene = Scene::new(etl_sim::simulate::images::shifted(truth, first, square_mm), e_ma, block, z, size);
        let opts = RenderOptions {
            optics: Optics::paper_focus(truth, e_ma, options.aperture_mm),
            photometry: options.photometry,
            seed: seed.wrapping_add(n as u64 * 104_729),
            ..RenderOptions::default()
        };
        let image = render(&scene, &opts)?.image.to_dynamic();
        let det = etl_image::detect::detect_dynamic(
            &image,
            etl_image::detect::Pattern::new(block.inner_corners[0], block.inner_corners[1])?,
        )?;
        out.push(
            det.indexed()
                .map(|([i, j], p)| ([(i0 + i) as f64 * square_mm, (j0 + j) as f64 * square_mm], p))
                .collect::<Vec<_>>(),
        );
    }
    let b = out.pop().unwrap_or_default();
    let a = out.pop().unwrap_or_default();
    Ok((a, b))
}
