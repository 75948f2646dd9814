//! The one-standard-error rule over the candidates' held-out errors (module docs of
//! [`super`]).

use etl_core::calib::Layout;
use etl_core::model::DistortionModel;
use etl_formats::model_selection::{ModelCandidate, ModelSelection};
use etl_formats::{Error, Result};

use super::held_out::HeldOut;
use super::{Fitted, METHOD, RULE};

/// The excess of `m` over the best `b` and its standard error (module docs), px^2: the
/// larger of the paired spread over views and the noise model's.
fn excess(m: &[HeldOut], b: &[HeldOut]) -> (f64, f64) {
    let em: Vec<(f64, usize)> = m.iter().map(HeldOut::error).collect();
    let eb: Vec<(f64, usize)> = b.iter().map(HeldOut::error).collect();
    let total: usize = em.iter().map(|x| x.1).sum();
    let k = em.iter().filter(|x| x.1 > 0).count();
    if total == 0 || k < 2 {
        return (0.0, 0.0);
    }
    let w = |n: usize| n as f64 / total as f64;
    let d: Vec<(f64, f64)> =
        em.iter().zip(&eb).filter(|(x, _)| x.1 > 0).map(|(x, y)| (w(x.1), (x.0 - y.0) / x.1 as f64)).collect();
    let mean: f64 = d.iter().map(|(w, d)| w * d).sum();
    let spread: f64 = d.iter().map(|(w, d)| w * w * (d - mean).powi(2)).sum::<f64>() * k as f64 / (k - 1) as f64;
    let noise: f64 = m.iter().zip(b).map(|(m, b)| b.difference_variance(m)).sum::<f64>() / (total * total) as f64;
    (mean, spread.max(noise).sqrt())
}

/// A candidate's held-out mean error per point, px^2.
fn mse(held_out: &[HeldOut]) -> f64 {
    let (s, n) = held_out.iter().map(HeldOut::error).fold((0.0, 0), |(s, n), (e, k)| (s + e, n + k));
    s / n.max(1) as f64
}

/// The comparison table and the index of the chosen candidate (module docs' rule).
pub(super) fn table(
    fits: &[(Layout, std::result::Result<Fitted, String>)],
    errors: &[std::result::Result<Vec<HeldOut>, String>],
) -> Result<(ModelSelection, usize)> {
    let ok: Vec<(usize, &Vec<HeldOut>)> = errors
        .iter()
        .enumerate()
        .filter_map(|(i, e)| e.as_ref().ok().map(|e| (i, e)))
        .filter(|(_, e)| mse(e).is_finite())
        .collect();
    let best = ok.iter().min_by(|a, b| mse(a.1).total_cmp(&mse(b.1))).map(|(i, _)| *i).ok_or_else(|| {
        let why: Vec<String> = fits
            .iter()
            .zip(errors)
            .filter_map(|((l, _), e)| {
                e.as_ref().err().map(|e| format!("{} degree {}: {e}", l.model().name(), l.focal_degree()))
            })
            .collect();
        Error::invalid("model_selection", format!("model selection: no candidate could be fitted ({})", why.join("; ")))
    })?;
    let best_errors = errors[best].as_ref().map_err(|e| Error::invalid("model_selection", e.clone()))?;
    let simplicity = |l: &Layout| (l.len(), l.model() != DistortionModel::Paper, l.focal_degree());
    let mut chosen = best;
    let mut rows = vec![];
    for (i, ((layout, fit), e)) in fits.iter().zip(errors).enumerate() {
        let mut row = ModelCandidate {
            distortion_model: layout.model().name().into(),
            focal_degree: layout.focal_degree(),
            parameters: layout.len(),
            fit_rms_px: fit.as_ref().ok().map(|f| f.solved.report.rms_px),
            prediction_rms_px: None,
            excess_mse_px2: None,
            excess_se_px2: None,
            chosen: false,
            error: e.as_ref().err().cloned(),
        };
        if let Ok(e) = e {
            let (d, se) = excess(e, best_errors);
            row.prediction_rms_px = Some(mse(e).sqrt());
            row.excess_mse_px2 = Some(d.max(0.0));
            row.excess_se_px2 = Some(se);
            if mse(e).is_finite() && d <= se && simplicity(layout) < simplicity(&fits[chosen].0) {
                chosen = i;
            }
        }
        rows.push(row);
    }
    rows[chosen].chosen = true;
    Ok((ModelSelection { method: METHOD.into(), rule: RULE.into(), candidates: rows }, chosen))
}
