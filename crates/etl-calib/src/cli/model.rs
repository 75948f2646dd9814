//! `etlcal model`: the paper rig's camera model (Eq. 16-18) and the lens physics (Eq. 8,
//! 10) over a range of currents, or, with `--fit-degrees`, the RMSE of polynomials of
//! degree 1..6 fitted to the physics f_com (the paper's Fig. 5).

use etl_core::fit::PolyFit;
use etl_core::model::CameraModel;
use etl_core::physics::LensPhysics;
use serde_json::json;

use super::print_json;
use crate::error::{Error, Result};

/// Most rows a table or fit may have (guards against a typo such as `--step 1e-9`).
const MAX_ROWS: usize = 10_000_000;

/// Arguments of `etlcal model`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// First current, mA.
    #[arg(long, value_name = "MA", default_value_t = 0.0)]
    pub from: f64,
    /// Last current, mA (included when the steps land on it).
    #[arg(long, value_name = "MA", default_value_t = 250.0)]
    pub to: f64,
    /// Step between currents, mA [default: 10 for the table, 0.1 with --fit-degrees].
    #[arg(long, value_name = "MA")]
    pub step: Option<f64>,
    /// Fit polynomials of degree 1..6 in E to f_com over [from, to] and print their RMSE
    /// (Fig. 5).
    #[arg(long)]
    pub fit_degrees: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

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
        k1: d.k1,
        p1: d.p1,
        p2: d.p2,
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

/// Runs `etlcal model`.
pub fn run(args: Args) -> Result<()> {
    let cam = CameraModel::paper_rig();
    let lens = LensPhysics::paper();
    if args.fit_degrees {
        let step = args.step.unwrap_or(0.1);
        let es = currents(args.from, args.to, step)?;
        let rmse = fit_rmse_mm(&lens, &es)?;
        if args.json {
            print_json(&json!({
                "fit_rmse_mm": rmse,
                "degrees": [1, 2, 3, 4, 5, 6],
                "from_ma": args.from,
                "to_ma": es.last().copied().unwrap_or(args.to),
                "step_ma": step,
                "samples": es.len(),
            }));
        } else {
            outln!(
                "Polynomial fits of the physics f_com(E) over {} .. {} mA ({} samples, Fig. 5):",
                args.from,
                args.to,
                es.len()
            );
            outln!("degree  RMSE (mm)");
            for (d, r) in rmse.iter().enumerate() {
                outln!("{:>6}  {:.4e}", d + 1, r);
            }
        }
        return Ok(());
    }
    let es = currents(args.from, args.to, args.step.unwrap_or(10.0))?;
    let rows = es.iter().map(|&e| model_row(&cam, &lens, e)).collect::<Result<Vec<_>>>()?;
    if args.json {
        print_json(&json!({ "rig": "paper", "rows": rows }));
    } else {
        outln!("Paper rig (section 5.1.2) and lens physics (section 5.1.1):");
        outln!(
            "{:>8} {:>10} {:>10} {:>12} {:>12} {:>12} {:>10} {:>10}",
            "E (mA)",
            "fx (px)",
            "fy (px)",
            "k1 (1/px2)",
            "p1 (1/px)",
            "p2 (1/px)",
            "f_liq(mm)",
            "f_com(mm)"
        );
        for r in &rows {
            outln!(
                "{:>8.2} {:>10.3} {:>10.3} {:>12.4e} {:>12.4e} {:>12.4e} {:>10.4} {:>10.5}",
                r.e_ma,
                r.fx_px,
                r.fy_px,
                r.k1,
                r.p1,
                r.p2,
                r.f_liq_mm,
                r.f_com_mm
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn currents_include_the_end_and_refuse_bad_ranges() {
        let e = currents(0.0, 260.0, 0.1).unwrap();
        assert_eq!(e.len(), 2601);
        assert_eq!(*e.last().unwrap(), 260.0);
        assert_eq!(currents(5.0, 5.0, 1.0).unwrap(), vec![5.0]);
        assert!(currents(f64::NAN, 1.0, 1.0).is_err());
        assert!(currents(0.0, 1.0, 0.0).is_err());
        assert!(currents(2.0, 1.0, 1.0).is_err());
        assert!(currents(0.0, 1e9, 1e-3).is_err());
    }
}
