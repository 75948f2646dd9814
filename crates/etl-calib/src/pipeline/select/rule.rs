//! The one-standard-error rule over the candidates' held-out errors (module docs of
//! [`super`]).

use etl_core::calib::Layout;
use etl_core::model::DistortionModel;
use etl_formats::model_selection::{ModelCandidate, ModelSelection};
use etl_formats::{Error, Result};

use super::held_out::HeldOut;
use super::{Fitted, METHOD, RULE};

/// One candidate's held-out views and each view's (error px^2, points), computed once.
struct Scored<'a> {
    views: &'a [HeldOut],
    errors: Vec<(f64, usize)>,
    /// Mean error per point, px^2.
    mse: f64,
}

impl<'a> Scored<'a> {
    fn new(views: &'a [HeldOut]) -> Self {
        let errors: Vec<(f64, usize)> = views.iter().map(HeldOut::error).collect();
        let (s, n) = errors.iter().fold((0.0, 0), |(s, n), (e, k)| (s + e, n + k));
        Scored { views, errors, mse: s / n.max(1) as f64 }
    }
}

/// The excess of `m` over the best `b` and its standard error (module docs), px^2: the
/// larger of the paired spread over views and the noise model's.
fn excess(m: &Scored<'_>, b: &Scored<'_>) -> (f64, f64) {
    let total: usize = m.errors.iter().map(|x| x.1).sum();
    let k = m.errors.iter().filter(|x| x.1 > 0).count();
    if total == 0 || k < 2 {
        return (0.0, 0.0);
    }
    let w = |n: usize| n as f64 / total as f64;
    let d: Vec<(f64, f64)> = m
        .errors
        .iter()
        .zip(&b.errors)
        .filter(|(x, _)| x.1 > 0)
        .map(|(x, y)| (w(x.1), (x.0 - y.0) / x.1 as f64))
        .collect();
    let mean: f64 = d.iter().map(|(w, d)| w * d).sum();
    let spread: f64 = d.iter().map(|(w, d)| w * w * (d - mean).powi(2)).sum::<f64>() * k as f64 / (k - 1) as f64;
    let noise: f64 =
        m.views.iter().zip(b.views).map(|(m, b)| b.difference_variance(m)).sum::<f64>() / (total * total) as f64;
    (mean, spread.max(noise).sqrt())
}

/// The comparison table and the index of the chosen candidate (module docs' rule).
pub(super) fn table(
    fits: &[(Layout, std::result::Result<Fitted, String>)],
    errors: &[std::result::Result<Vec<HeldOut>, String>],
) -> Result<(ModelSelection, usize)> {
    let scored: Vec<Option<Scored<'_>>> = errors.iter().map(|e| e.as_ref().ok().map(|v| Scored::new(v))).collect();
    let ok: Vec<(usize, &Scored<'_>)> = scored
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.as_ref().map(|s| (i, s)))
        .filter(|(_, s)| s.mse.is_finite())
        .collect();
    let best = ok.iter().min_by(|a, b| a.1.mse.total_cmp(&b.1.mse)).map(|(i, _)| *i).ok_or_else(|| {
        let why: Vec<String> = fits
            .iter()
            .zip(errors)
            .filter_map(|((l, _), e)| {
                e.as_ref().err().map(|e| format!("{} degree {}: {e}", l.model().name(), l.focal_degree()))
            })
            .collect();
        Error::invalid("model_selection", format!("model selection: no candidate could be fitted ({})", why.join("; ")))
    })?;
    let best_scored =
        scored[best].as_ref().ok_or_else(|| Error::invalid("model_selection", "the best candidate has no errors"))?;
    let simplicity = |l: &Layout| (l.len(), l.moving_centre(), l.model() != DistortionModel::Paper, l.focal_degree());
    let mut chosen = best;
    let mut rows = vec![];
    for (i, (((layout, fit), e), s)) in fits.iter().zip(errors).zip(&scored).enumerate() {
        let mut row = ModelCandidate {
            distortion_model: layout.model().name().into(),
            focal_degree: layout.focal_degree(),
            centre: layout.moving_centre().then(|| "moving".to_owned()),
            parameters: layout.len(),
            fit_rms_px: fit.as_ref().ok().map(|f| f.solved.report.rms_px),
            prediction_rms_px: None,
            excess_mse_px2: None,
            excess_se_px2: None,
            chosen: false,
            error: e.as_ref().err().cloned(),
        };
        if let Some(s) = s {
            let (d, se) = excess(s, best_scored);
            row.prediction_rms_px = Some(s.mse.sqrt());
            row.excess_mse_px2 = Some(d.max(0.0));
            row.excess_se_px2 = Some(se);
            if s.mse.is_finite() && d <= se && simplicity(layout) < simplicity(&fits[chosen].0) {
                chosen = i;
            }
        }
        rows.push(row);
    }
    rows[chosen].chosen = true;
    Ok((ModelSelection { method: METHOD.into(), rule: RULE.into(), candidates: rows }, chosen))
}
