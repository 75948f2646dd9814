//! `etlcal model`: the paper rig's camera model (Eq. 16-18) and the lens physics (Eq. 8,
//! 10) over a range of currents, or, with `--fit-degrees`, the RMSE of polynomials of
//! degree 1..6 fitted to the physics f_com (the paper's Fig. 5).

use etl_core::model::CameraModel;
use etl_core::physics::LensPhysics;
use serde_json::json;

use super::print_json;
use etl_formats::Result;
use etl_studies::model::{currents, fit_rmse_mm, model_row};

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
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
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
