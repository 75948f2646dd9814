//! Observations as borrowed slices: views, each with its compensated current and points.

use serde::{Deserialize, Serialize};

use crate::error::{all_finite, Error, Result};

/// One observed calibration point: its world position (mm) and observed pixel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// World coordinates, mm (the stage frame: Z_W is the stage position of the view).
    pub world_mm: [f64; 3],
    /// Observed (distorted) pixel.
    pub pixel: [f64; 2],
}

/// The points of one view, taken at compensated current `e_com_ma`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View<'a> {
    /// Compensated lens current E_com, mA.
    pub e_com_ma: f64,
    /// The view's points.
    pub points: &'a [Point],
}

/// Checks what every solver needs: finite numbers and no empty view.
pub fn validate(views: &[View<'_>]) -> Result<()> {
    if views.is_empty() {
        return Err(Error::TooFew { what: "views", needed: 1, got: 0 });
    }
    for v in views {
        if !v.e_com_ma.is_finite() {
            return Err(Error::NotFinite { what: "view current e_com_ma" });
        }
        if v.points.is_empty() {
            return Err(Error::InvalidArgument { what: "a view has no points" });
        }
        for p in v.points {
            all_finite(&p.world_mm, "world_mm of a point")?;
            all_finite(&p.pixel, "pixel of a point")?;
        }
    }
    Ok(())
}

/// Number of distinct currents among the views (equal within 1e-9 mA).
pub fn distinct_currents(views: &[View<'_>]) -> usize {
    let mut n = 0;
    for (i, v) in views.iter().enumerate() {
        if views.iter().take(i).all(|w| (w.e_com_ma - v.e_com_ma).abs() > 1e-9) {
            n += 1;
        }
    }
    n
}

/// Total number of points.
pub fn point_count(views: &[View<'_>]) -> usize {
    views.iter().map(|v| v.points.len()).sum()
}
