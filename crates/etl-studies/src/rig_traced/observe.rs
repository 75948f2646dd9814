//! What the traced cameras see at run time: a random point both see at given currents,
//! and the board at a stage position, as traced pixels (the rig's kind of corner) plus
//! pixel noise.

use etl_formats::{Error, Result};
use etl_sim::optics::multi_camera::TracedMultiCamera;
use etl_sim::optics::rig::Setting;
use etl_sim::simulate::gauss;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::rig_triangulation::moves::BoardPixels;

/// How many random points are drawn before a trial gives up finding one both cameras see.
const MAX_DRAWS: usize = 200;

/// Both cameras at `e_com_ma`.
pub fn settings(rig: &TracedMultiCamera, e_com_ma: [f64; 2]) -> Result<[Setting; 2]> {
    Ok([rig.cameras[0].optics.at(e_com_ma[0])?, rig.cameras[1].optics.at(e_com_ma[1])?])
}

/// A point uniform in the stage's volume (X, Y over the board, Z over the travel) that
/// both cameras see at `at`, and its noise-free traced pixels; None after [`MAX_DRAWS`].
pub fn draw_point(
    rig: &TracedMultiCamera,
    at: &[Setting; 2],
    rng: &mut ChaCha8Rng,
) -> Option<([f64; 3], [[f64; 2]; 2])> {
    let b = &rig.board;
    let span = |n: usize| b.square_mm * (n - 1) as f64;
    let [z0, z1] = rig.stage_travel_mm;
    (0..MAX_DRAWS).find_map(|_| {
        let w = [
            rng.random_range(0.0..=span(b.inner_corners[0])),
            rng.random_range(0.0..=span(b.inner_corners[1])),
            rng.random_range(z0..=z1),
        ];
        let p0 = rig.cameras[0].pixel(&at[0], w, rig.corner)?;
        let p1 = rig.cameras[1].pixel(&at[1], w, rig.corner)?;
        Some((w, [p0, p1]))
    })
}

/// `px` plus Gaussian noise of `sigma_px` per coordinate.
pub fn noisy(px: [f64; 2], sigma_px: f64, rng: &mut ChaCha8Rng) -> [f64; 2] {
    [px[0] + gauss(sigma_px, rng), px[1] + gauss(sigma_px, rng)]
}

/// Every board corner (row-major, first inner corner at the origin) at stage position
/// `z_mm` in each camera at `e_com_ma`: its traced pixel plus noise, None where unseen.
pub fn board_pixels(
    rig: &TracedMultiCamera,
    z_mm: f64,
    e_com_ma: [f64; 2],
    sigma_px: f64,
    rng: &mut ChaCha8Rng,
) -> Result<BoardPixels> {
    let at = settings(rig, e_com_ma)?;
    let corners = corners_mm(rig);
    let clean: Vec<[Option<[f64; 2]>; 2]> = corners
        .par_iter()
        .map(|c| std::array::from_fn(|k| rig.cameras[k].pixel(&at[k], [c[0], c[1], z_mm], rig.corner)))
        .collect();
    if clean.is_empty() {
        return Err(Error::invalid("board", "board: no corners"));
    }
    Ok(clean.into_iter().map(|o| o.map(|p| p.map(|p| noisy(p, sigma_px, rng)))).collect())
}

/// The board's corners (row-major), mm.
pub fn corners_mm(rig: &TracedMultiCamera) -> Vec<[f64; 2]> {
    let [cols, rows] = rig.board.inner_corners;
    let s = rig.board.square_mm;
    (0..cols * rows).map(|i| [s * (i % cols) as f64, s * (i / cols) as f64]).collect()
}
