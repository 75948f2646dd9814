//! The paper rig's camera model and lens physics over a range of currents (`etlcal
//! model`), and the modelling error of polynomial fits of f_com(E) (Fig. 5).

use etl_core::fit::PolyFit;
use etl_core::model::CameraModel;
use etl_core::physics::LensPhysics;

use etl_formats::{Error, Result};

/// Most rows a table or fit may have (guards against a typo such as `--step 1e-9`).
const MAX_ROWS: usize = 10_000_000;

/// One row of the table.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct ModelRow {
    /// Compensated current, mA.
    pub e_ma: f64,
    /// Focal length along u, px.
    pub fx_px: f64,
    /// Focal length along v, px.
    pub fy_px: f64,
    /// Radial distortion k1, 1/px^2.
    pub k1: f64,
    /// Decentering distortion p1, 1/px.
    pub p1: f64,
    /// Decentering distortion p2, 1/px.
    pub p2: f64,
    /// Focal length of the liquid lens (physics, Eq. 8), mm.
    pub f_liq_mm: f64,
    /// Compound focal length (physics, Eq. 10), mm.
    pub f_com_mm: f64,
}

/// The currents from, from + step, ... <= to. Errors: non-finite numbers, step <= 0,
/// from > to, too many rows.
pub fn currents(from: f64, to: f64, step: f64) -> Result<Vec<f64>> {
    for (name, v) in [("--from", from), ("--to", to), ("--step", step)] {
        if !v.is_finite() {
            return Err(Error::InvalidInput(format!("{name} = {v} is not a finite number of mA")));
        }
    }
    if step <= 0.0 {
        return Err(Error::InvalidInput(format!("--step = {step} must be positive")));
    }
    if from > to {
        return Err(Error::InvalidInput(format!("--from = {from} is above --to = {to}")));
    }
    // A hair of slack so that 0..260 by 0.1 includes 260.
    let n = ((to - from) / step * (1.0 + 1e-12)).floor();
    if n >= MAX_ROWS as f64 {
        return Err(Error::InvalidInput(format!("[--from, --to] / --step gives more than {MAX_ROWS} currents")));
    }
    Ok((0..=n as usize).map(|i| (from + i as f64 * step).min(to)).collect())
}

/// The table row at current `e_ma` for the paper rig and the paper's lens physics.
pub fn model_row(cam: &CameraModel, lens: &LensPhysics, e_ma: f64) -> Result<ModelRow> {
    let at = |e: etl_core::Error| Error::InvalidInput(format!("at E = {e_ma} mA: {e}"));
    let k = cam.intrinsics(e_ma).map_err(at)?;
    let d = cam.distortion(e_ma).map_err(at)?;
    Ok(ModelRow {
        e_ma,
        fx_px: k.fx,
        fy_px: k.fy,
        k1: d.padded()[0],
        p1: d.padded()[1],
        p2: d.padded()[2],
        f_liq_mm: lens.f_liq_mm(e_ma).map_err(at)?,
        f_com_mm: lens.f_com_mm(e_ma).map_err(at)?,
    })
}

/// RMSE (mm) of the least-squares polynomials of degree 1..6 through f_com(E) sampled at
/// `currents` (Fig. 5). Needs at least two distinct currents, and 7 for degree 6.
pub fn fit_rmse_mm(lens: &LensPhysics, currents: &[f64]) -> Result<[f64; 6]> {
    let (Some(&lo), Some(&hi)) = (currents.first(), currents.last()) else {
        return Err(Error::InvalidInput("no currents to fit".into()));
    };
    let mut values = Vec::with_capacity(currents.len());
    for &e in currents {
        let f = lens.f_com_mm(e).map_err(|err| Error::InvalidInput(format!("at E = {e} mA: {err}")))?;
        values.push((e, f));
    }
    let mut out = [0.0; 6];
    for (d, r) in out.iter_mut().enumerate() {
        let mut fit = PolyFit::new(d + 1, [lo, hi])?;
        for &(e, f) in &values {
            fit.add(e, f)?;
        }
        *r = fit.solve()?.1;
    }
    Ok(out)
}
