//! `etlcal study fig5`: the modelling error of polynomials of degree 1..6 in E fitted to the
//! physics focal length f_com(E) (Eq. 8, 10 with the section 5.1.1 values) over
//! 0..260 mA (the paper's section 5.1.1 and Fig. 5). The paper adopts the cubic, whose
//! RMSE it gives as 1.09e-3 mm.

use etl_core::fit::PolyFit;
use etl_core::physics::LensPhysics;
use serde_json::json;

use super::common::{md_table, sci, Chart, Figure, Series, StudyOutput};
use crate::model::{currents, fit_rmse_mm};
use etl_formats::{Error, Result};

/// The paper's RMSE of the cubic, mm.
pub const PAPER_CUBIC_RMSE_MM: f64 = 1.09e-3;
/// The fitted range, mA.
pub const RANGE_MA: [f64; 2] = [0.0, 260.0];
/// Sampling step of the fit, mA.
pub const STEP_MA: f64 = 0.1;

/// Result of the Fig. 5 study.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Fig5 {
    /// RMSE of the fits of degree 1..6, mm.
    pub fit_rmse_mm: [f64; 6],
    /// Residual f_com - cubic over the range (E mA, residual mm), every 2 mA.
    pub cubic_residual_mm: Vec<(f64, f64)>,
}

/// Runs the study (deterministic: no trials).
///
/// ```
/// let f = etl_studies::fig5::fig5().unwrap();
/// // The cubic's RMSE over 0..260 mA is the paper's 1.09e-3 mm within 1 %.
/// assert!((f.fit_rmse_mm[2] / 1.09e-3 - 1.0).abs() < 0.01);
/// let out = f.output();
/// assert_eq!(out.json["fit_rmse_mm"].as_array().unwrap().len(), 6);
/// ```
pub fn fig5() -> Result<Fig5> {
    let lens = LensPhysics::paper();
    let es = currents(RANGE_MA[0], RANGE_MA[1], STEP_MA)?;
    let fit_rmse_mm = fit_rmse_mm(&lens, &es)?;
    let mut fit = PolyFit::new(3, RANGE_MA)?;
    let mut f = Vec::with_capacity(es.len());
    for &e in &es {
        let v = lens.f_com_mm(e).map_err(|err| Error::invalid_value("e_ma", e, format!("at E = {e} mA: {err}")))?;
        fit.add(e, v)?;
        f.push((e, v));
    }
    let (cubic, _) = fit.solve()?;
    let cubic_residual_mm = f
        .iter()
        .step_by(20)
        .map(|&(e, v)| Ok((e, v - cubic.eval(e)?)))
        .collect::<std::result::Result<Vec<_>, etl_core::Error>>()?;
    Ok(Fig5 { fit_rmse_mm, cubic_residual_mm })
}

impl Fig5 {
    /// JSON, markdown and plots.
    pub fn output(&self) -> StudyOutput {
        let rows: Vec<Vec<String>> = self
            .fit_rmse_mm
            .iter()
            .enumerate()
            .map(|(d, r)| {
                let paper = if d == 2 { sci(PAPER_CUBIC_RMSE_MM) } else { "(plot only)".into() };
                vec![(d + 1).to_string(), sci(*r), paper]
            })
            .collect();
        let markdown = format!(
            "# Fig. 5: polynomial models of the physics focal length\n\nf_com(E) from the lens physics (Eq. 8, 10, \
             section 5.1.1 values) sampled every {STEP_MA} mA over {} .. {} mA; least-squares polynomials of degree 1..6.\n\n{}\n\
             Cubic: {:.4e} mm against the paper's {:.2e} mm ({:+.1} %).\n",
            RANGE_MA[0],
            RANGE_MA[1],
            md_table(&["degree", "RMSE etlcal (mm)", "RMSE paper (mm)"], &rows),
            self.fit_rmse_mm[2],
            PAPER_CUBIC_RMSE_MM,
            100.0 * (self.fit_rmse_mm[2] / PAPER_CUBIC_RMSE_MM - 1.0)
        );
        let fig = Figure {
            name: "fig5".into(),
            grid: (1, 2),
            panels: vec![
                Chart {
                    title: "(a) RMSE of the polynomial fits of f_com(E)".into(),
                    x_label: "degree".into(),
                    y_label: "RMSE (mm)".into(),
                    log_y: true,
                    series: vec![
                        Series::line(
                            "etlcal",
                            0,
                            self.fit_rmse_mm.iter().enumerate().map(|(d, r)| ((d + 1) as f64, *r)).collect(),
                        ),
                        Series::scatter("paper (cubic)", 1, vec![(3.0, PAPER_CUBIC_RMSE_MM)]),
                    ],
                    x_names: vec![],
                },
                Chart {
                    title: "(b) residual of the cubic".into(),
                    x_label: "E_com (mA)".into(),
                    y_label: "f_com - cubic (um)".into(),
                    log_y: false,
                    series: vec![Series::reference(
                        "f_com - cubic",
                        0,
                        self.cubic_residual_mm.iter().map(|&(e, r)| (e, 1000.0 * r)).collect(),
                    )],
                    x_names: vec![],
                },
            ],
        };
        StudyOutput {
            name: "fig5".into(),
            json: json!({
                "fit_rmse_mm": self.fit_rmse_mm,
                "degrees": [1, 2, 3, 4, 5, 6],
                "range_ma": RANGE_MA,
                "step_ma": STEP_MA,
                "paper_cubic_rmse_mm": PAPER_CUBIC_RMSE_MM,
            }),
            markdown,
            figures: vec![fig],
        }
    }
}
