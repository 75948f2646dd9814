//! Waiting for the lens from the frames themselves, not by a fixed sleep.
//!
//! - [`settle_on_corners`]: frames are grabbed until the board's detected corners stop
//!   moving: the RMS displacement of the corners two consecutive frames share is at most
//!   [`super::CaptureOptions::settle_tolerance_px`]. A lens still moving (its step
//!   response, creep) moves the corners, since the magnification follows the power.
//! - [`settle_on_sharpness`] (for autofocus, where the board may be too blurred to
//!   detect): until two consecutive frames' Tenengrad sharpness differ by at most
//!   [`SHARPNESS_TOLERANCE`] (relative).
//!
//! Both give up after [`super::CaptureOptions::settle_timeout_s`] of wall time, with an
//! error naming the lens and how far it still moved.

use std::time::Instant;

use etl_formats::board::Board;
use etl_image::board::{detect_board_dynamic, BoardDetection};
use etl_image::sharpness::{sharpness, sharpness_u16, Metric};

use super::CaptureOptions;
use crate::camera::{Camera, Frame, Pixels};
use crate::error::{Error, ErrorKind, Result};

/// Two sharpness values agree when they differ by at most this fraction.
pub const SHARPNESS_TOLERANCE: f64 = 0.01;

/// The RMS distance of the corners `a` and `b` share (by id), px; `None` if they share
/// fewer than 4.
pub fn corner_motion_px(a: &BoardDetection, b: &BoardDetection) -> Option<f64> {
    let mut sum = 0.0;
    let mut n = 0usize;
    for (id, p) in a.ids.iter().zip(&a.corners_px) {
        if let Ok(k) = b.ids.binary_search(id) {
            let q = b.corners_px[k];
            sum += (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
            n += 1;
        }
    }
    (n >= 4).then(|| (sum / n as f64).sqrt())
}

/// Detects `board` in a frame.
pub fn detect(frame: &Pixels, board: &Board) -> etl_formats::Result<BoardDetection> {
    detect_board_dynamic(&frame.to_dynamic(), board)
}

/// Grabs frames until the corners of `board` stop moving (module docs); returns the
/// last frame. `lens` names the device a time-out blames; `view` the view refused when no
/// frame showed the board at all.
pub fn settle_on_corners(
    camera: &mut dyn Camera,
    board: &Board,
    options: &CaptureOptions,
    lens: &str,
    view: &str,
) -> Result<Frame> {
    let start = Instant::now();
    let mut previous: Option<BoardDetection> = None;
    let mut last_motion = None;
    let mut last_error = None;
    let mut seen = false;
    loop {
        let frame = camera.grab()?;
        match detect(&frame.pixels, board) {
            Ok(d) => {
                seen = true;
                if let Some(motion) = previous.as_ref().and_then(|p| corner_motion_px(p, &d)) {
                    if motion <= options.settle_tolerance_px {
                        return Ok(frame);
                    }
                    last_motion = Some(motion);
                }
                previous = Some(d);
            }
            Err(e) => {
                previous = None;
                last_error = Some(e.to_string());
            }
        }
        if start.elapsed().as_secs_f64() > options.settle_timeout_s {
            if !seen {
                let e = last_error.unwrap_or_default();
                return Err(Error::view(
                    view,
                    format!("no board in any frame within {} s ({e})", options.settle_timeout_s),
                ));
            }
            let why = match (last_motion, last_error) {
                (Some(m), _) => format!("the board's corners still moved {m:.3} px between frames"),
                (None, Some(e)) => format!("the board came and went in the frames ({e})"),
                (None, None) => "no two frames to compare".to_owned(),
            };
            let message = format!(
                "did not settle within {} s (tolerance {} px): {why}",
                options.settle_timeout_s, options.settle_tolerance_px
            );
            return Err(Error::device(lens, ErrorKind::Timeout, message));
        }
    }
}

/// The Tenengrad sharpness of a frame.
pub fn frame_sharpness(pixels: &Pixels) -> etl_formats::Result<f64> {
    match pixels {
        Pixels::Mono8(g) => sharpness(g, Metric::Tenengrad),
        Pixels::Mono16(g) => sharpness_u16(g, Metric::Tenengrad),
    }
}

/// Grabs frames until two consecutive sharpness values agree (module docs); returns the
/// last frame and its sharpness.
pub fn settle_on_sharpness(camera: &mut dyn Camera, options: &CaptureOptions, lens: &str) -> Result<(Frame, f64)> {
    let start = Instant::now();
    let mut previous: Option<f64> = None;
    loop {
        let frame = camera.grab()?;
        let s = frame_sharpness(&frame.pixels)?;
        if let Some(p) = previous {
            if (s - p).abs() <= SHARPNESS_TOLERANCE * p.abs().max(s.abs()) {
                return Ok((frame, s));
            }
        }
        previous = Some(s);
        if start.elapsed().as_secs_f64() > options.settle_timeout_s {
            let message = format!(
                "did not settle within {} s: the sharpness still changed by more than {} % between frames",
                options.settle_timeout_s,
                100.0 * SHARPNESS_TOLERANCE
            );
            return Err(Error::device(lens, ErrorKind::Timeout, message));
        }
    }
}
