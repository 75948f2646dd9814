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

/// A point uniform in the stage's volume: X, Y over the board, Z over the travel.
fn volume_point(rig: &TracedMultiCamera, rng: &mut ChaCha8Rng) -> [f64; 3] {
    let b = &rig.board;
    let span = |n: usize| b.square_mm * (n - 1) as f64;
    let [z0, z1] = rig.stage_travel_mm;
    [
        rng.random_range(0.0..=span(b.inner_corners[0])),
        rng.random_range(0.0..=span(b.inner_corners[1])),
        rng.random_range(z0..=z1),
    ]
}

/// The noise-free traced pixels of world point `w` in both cameras at `at`; None where a
/// camera does not see it.
fn both_pixels(rig: &TracedMultiCamera, at: &[Setting; 2], w: [f64; 3]) -> Option<[[f64; 2]; 2]> {
    Some([rig.cameras[0].pixel(&at[0], w, rig.corner)?, rig.cameras[1].pixel(&at[1], w, rig.corner)?])
}

/// A point uniform in the stage's volume (X, Y over the board, Z over the travel) that
/// both cameras see at `at`, and its noise-free traced pixels; None after `MAX_DRAWS`
/// draws.
pub fn draw_point(
    rig: &TracedMultiCamera,
    at: &[Setting; 2],
    rng: &mut ChaCha8Rng,
) -> Option<([f64; 3], [[f64; 2]; 2])> {
    (0..MAX_DRAWS).find_map(|_| {
        let w = volume_point(rig, rng);
        Some((w, both_pixels(rig, at, w)?))
    })
}

/// A random point of a trial: both cameras' currents, the world point, its noise-free
/// traced pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drawn {
    /// Each camera's E_com, mA.
    pub e_com_ma: [f64; 2],
    /// The point, world frame, mm.
    pub world_mm: [f64; 3],
    /// Its traced pixel in each camera.
    pub pixels: [[f64; 2]; 2],
}

/// A point uniform in the stage's volume, each camera focused on it (its current the one
/// that puts its depth in focus: [`etl_sim::optics::multi_camera::focus::FocusTable::current_ma`]), with both
/// currents inside `ranges_ma` and the point seen by both: its currents, the point and
/// its noise-free traced pixels; None after `MAX_DRAWS` draws. What an autofocusing rig
/// measures: no run-time point is out of focus.
pub fn draw_focused_point(rig: &TracedMultiCamera, ranges_ma: [[f64; 2]; 2], rng: &mut ChaCha8Rng) -> Option<Drawn> {
    (0..MAX_DRAWS).find_map(|_| {
        let w = volume_point(rig, rng);
        let focus = |k: usize| {
            let c = &rig.cameras[k];
            let e = c.focus.current_ma(c.world_to_camera(w)[2])?;
            (ranges_ma[k][0]..=ranges_ma[k][1]).contains(&e).then_some(e)
        };
        let e = [focus(0)?, focus(1)?];
        let pixels = both_pixels(rig, &settings(rig, e).ok()?, w)?;
        Some(Drawn { e_com_ma: e, world_mm: w, pixels })
    })
}

/// The defocus of world point `w_mm` in each camera at `e_com_ma`, dioptres: 1000 / its
/// depth - 1000 / the camera's distance in focus there (both camera z, mm: the focus
/// table's). Errors: a current outside a camera's focus table.
pub fn defocus_dpt(rig: &TracedMultiCamera, e_com_ma: [f64; 2], w_mm: [f64; 3]) -> Result<[f64; 2]> {
    let one = |k: usize| -> Result<f64> {
        let c = &rig.cameras[k];
        let focus = c.focus.distance_at_mm(e_com_ma[k]).ok_or_else(|| {
            Error::invalid_value(
                "e_com_ma",
                e_com_ma[k],
                format!("e_com_ma: camera {k}'s focus table has no {} mA", e_com_ma[k]),
            )
        })?;
        Ok(1000.0 / c.world_to_camera(w_mm)[2] - 1000.0 / focus)
    };
    Ok([one(0)?, one(1)?])
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
