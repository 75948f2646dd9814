//! The numbers the report derives from the calibration's covariance C (p x p, order of
//! the model's [`Layout`] names; at capacity): the standard deviation of a curve value q(E)
//! (fx, fy and the first three distortion coefficients) as sqrt(J_q C J_q^T), the
//! correlation matrix, and the parameter table's names and units.

use etl_core::calib::jacobian::{from_params, to_params};
use etl_core::calib::params::{Layout, MAX_PARAMS};
use etl_core::calib::uncertainty::sandwich;
use etl_core::model::{CameraModel, DistortionModel, MAX_COEFFICIENTS};

/// Most curves the report draws against the current: fx, fy and up to five distortion
/// coefficients.
pub(crate) const MAX_CURVES: usize = 2 + MAX_COEFFICIENTS;

/// The values of one curve set (see [`curve_names`]), at capacity.
pub(crate) type CurveSet = [f64; MAX_CURVES];

/// The curves the report draws against the current for `model`'s family: fx, fy (px),
/// then the distortion coefficients (paper: k1 1/px^2, p1, p2 1/px; opencv: k1, k2, p1,
/// p2, k3, dimensionless), as (name, unit).
pub(crate) fn curve_names(model: &CameraModel) -> Vec<(&'static str, &'static str)> {
    let family = model.distortion_model();
    let unit = |c: &str| match family {
        DistortionModel::Paper if c == "k1" => "1/px²",
        DistortionModel::Paper => "1/px",
        DistortionModel::OpenCv => "none",
    };
    [("fx", "px"), ("fy", "px")].into_iter().chain(family.coefficient_names().iter().map(|&c| (c, unit(c)))).collect()
}

/// The values of [`curve_names`] at `e_com_ma`, at capacity (NaN where the model cannot
/// be evaluated, e.g. a non-positive focal length; zero past the family's count).
pub(crate) fn curve_values(model: &CameraModel, e_com_ma: f64) -> CurveSet {
    let (fx, fy) = model.focal_lengths(e_com_ma);
    let mut out = [f64::NAN; MAX_CURVES];
    out[0] = fx;
    out[1] = fy;
    if let Ok(d) = model.distortion(e_com_ma) {
        out[2..].copy_from_slice(d.padded());
    }
    out
}

/// One standard deviation of each of [`curve_names`] at `e_com_ma`: sqrt(J C J^T) with J = dq/dx
/// by central differences, the step of parameter i being 1e-4 of its own std (q is
/// polynomial in kf and a, so the difference is exact to rounding for the linear numbers
/// and to O(h^2) for w = 2 / (fx + fy)). Parameters with zero std (held) do not enter.
pub(crate) fn curve_std(model: &CameraModel, covariance: &[[f64; MAX_PARAMS]; MAX_PARAMS], e_com_ma: f64) -> CurveSet {
    let layout = model.layout();
    let x = to_params(model);
    let mut j = [[0.0; MAX_PARAMS]; MAX_CURVES];
    for i in 0..layout.len() {
        let h = 1e-4 * covariance[i][i].max(0.0).sqrt();
        if h == 0.0 {
            continue;
        }
        let (mut up, mut down) = (x, x);
        up[i] += h;
        down[i] -= h;
        let (qu, qd) =
            (curve_values(&from_params(&layout, &up), e_com_ma), curve_values(&from_params(&layout, &down), e_com_ma));
        for (k, row) in j.iter_mut().enumerate() {
            row[i] = (qu[k] - qd[k]) / (2.0 * h);
        }
    }
    let s = sandwich(&j, covariance);
    core::array::from_fn(|k| s[k][k].max(0.0).sqrt())
}

/// The correlation matrix r_ij = C_ij / sqrt(C_ii C_jj); 0 off the diagonal (and 1 on it)
/// for a held number (C_ii = 0), whose correlation is undefined.
pub(crate) fn correlation(covariance: &[[f64; MAX_PARAMS]; MAX_PARAMS]) -> [[f64; MAX_PARAMS]; MAX_PARAMS] {
    core::array::from_fn(|i| {
        core::array::from_fn(|j| {
            let s = (covariance[i][i] * covariance[j][j]).sqrt();
            if i == j {
                1.0
            } else if s > 0.0 {
                covariance[i][j] / s
            } else {
                0.0
            }
        })
    })
}

/// The pairs (i, j, r_ij), i < j < `n`, with |r_ij| > `threshold`, strongest first.
pub(crate) fn strong_pairs(r: &[[f64; MAX_PARAMS]; MAX_PARAMS], n: usize, threshold: f64) -> Vec<(usize, usize, f64)> {
    let n = n.min(MAX_PARAMS);
    let mut pairs: Vec<(usize, usize, f64)> =
        (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).map(|(i, j)| (i, j, r[i][j])).collect();
    pairs.retain(|p| p.2.abs() > threshold);
    pairs.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    pairs
}

/// The unit of number `i` of `layout`. fx(E) = sum kf_k E^k (px, E in mA, kf_k in
/// px/mA^k); each distortion coefficient c = a w^2 + b w + c0 with w = 2 / (fx + fy) in
/// 1/px, so its a carries c's unit times px^2 and its b c's unit times px. The paper's
/// k1 is in 1/px^2, its p1, p2 in 1/px; OpenCV's coefficients are dimensionless.
pub(crate) fn param_unit(layout: &Layout, i: usize) -> &'static str {
    const KF: [&str; 6] = ["px", "px/mA", "px/mA²", "px/mA³", "px/mA⁴", "px/mA⁵"];
    if layout.rotation().contains(i) {
        "rad"
    } else if layout.translation().contains(i) {
        "mm"
    } else if let Some(s) = [layout.kf_x(), layout.kf_y()].into_iter().find(|s| s.contains(i)) {
        KF.get(i - s.start).copied().unwrap_or("")
    } else if layout.principal_point().contains(i) {
        "px"
    } else {
        let k = i.saturating_sub(layout.distortion_a().start);
        let (coefficient, term) = (k / 3, k % 3);
        let paper_radial = layout.model() == DistortionModel::Paper && coefficient == 0;
        match (layout.model(), paper_radial, term) {
            (DistortionModel::Paper, true, 0) => "none",
            (DistortionModel::Paper, true, 1) => "1/px",
            (DistortionModel::Paper, true, _) => "1/px²",
            (DistortionModel::Paper, false, 0) => "px",
            (DistortionModel::Paper, false, 1) => "none",
            (DistortionModel::Paper, false, _) => "1/px",
            (DistortionModel::OpenCv, _, 0) => "px²",
            (DistortionModel::OpenCv, _, 1) => "px",
            (DistortionModel::OpenCv, _, _) => "none",
        }
    }
}

/// What number `i` of `layout` is, for the parameter table.
pub(crate) fn param_meaning(layout: &Layout, i: usize) -> String {
    let name = layout.name(i);
    match name {
        "om1" | "om2" | "om3" => "rotation (Rodrigues) world → camera".into(),
        "tx" | "ty" | "tz" => "translation world → camera".into(),
        n if n.starts_with("kf") && n.ends_with('x') => "fx(E) polynomial coefficient".into(),
        n if n.starts_with("kf") => "fy(E) polynomial coefficient".into(),
        "u0" | "v0" => "principal point".into(),
        _ => {
            let k = i.saturating_sub(layout.distortion_a().start) / 3;
            let c = layout.model().coefficient_names().get(k).copied().unwrap_or("?");
            let a = |t: usize| layout.name(layout.distortion_triple(k).at(t));
            format!("{c} = {} w² + {} w + {}", a(0), a(1), a(2))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use etl_core::calib::params::Span;
    const KF_X: Span = Span { start: 6, len: 4 };
    const DISTORTION_A: Span = Span { start: 16, len: 9 };
    const PARAMS: usize = MAX_PARAMS;

    /// A covariance with known entries on kf_x and a1..a3 (and a correlation between them).
    fn covariance() -> [[f64; PARAMS]; PARAMS] {
        let mut c = [[0.0; PARAMS]; PARAMS];
        let s = [2.0, 0.03, 2e-4, 5e-7];
        for i in 0..4 {
            for j in 0..4 {
                // r = 0.5 between different kf coefficients.
                c[KF_X.at(i)][KF_X.at(j)] = s[i] * s[j] * if i == j { 1.0 } else { 0.5 };
            }
        }
        for (k, s) in [1e-3, 1e-6, 1e-9].iter().enumerate() {
            c[DISTORTION_A.at(k)][DISTORTION_A.at(k)] = s * s;
        }
        c
    }

    #[test]
    fn fx_std_is_the_quadratic_form_of_the_powers_of_e() {
        let (m, c) = (CameraModel::paper_rig(), covariance());
        for e in [80.0, 150.0, 250.0] {
            let p = [1.0, e, e * e, e * e * e];
            let mut v = 0.0;
            for i in 0..4 {
                for j in 0..4 {
                    v += p[i] * p[j] * c[KF_X.at(i)][KF_X.at(j)];
                }
            }
            let s = curve_std(&m, &c, e);
            assert!((s[0] / v.sqrt() - 1.0).abs() < 1e-6, "fx std at {e}: {} vs {}", s[0], v.sqrt());
            // fy's numbers have no variance.
            assert_eq!(s[1], 0.0);
        }
    }

    #[test]
    fn k1_std_adds_the_a_terms_and_the_focal_term() {
        // Only a1..a3 uncertain: std k1 = sqrt(w^4 s1^2 + w^2 s2^2 + s3^2), w = 2 / (fx + fy).
        let m = CameraModel::paper_rig();
        let mut c = [[0.0; PARAMS]; PARAMS];
        for (k, s) in [1e-3, 1e-6, 1e-9].iter().enumerate() {
            c[DISTORTION_A.at(k)][DISTORTION_A.at(k)] = s * s;
        }
        let e = 120.0;
        let (fx, fy) = m.focal_lengths(e);
        let w = 2.0 / (fx + fy);
        let want = (w.powi(4) * 1e-6 + w * w * 1e-12 + 1e-18).sqrt();
        let s = curve_std(&m, &c, e);
        assert!((s[2] / want - 1.0).abs() < 1e-6, "{} vs {want}", s[2]);
        assert_eq!((s[0], s[3], s[4]), (0.0, 0.0, 0.0));
    }

    #[test]
    fn correlation_and_strong_pairs() {
        let r = correlation(&covariance());
        assert!((r[KF_X.at(0)][KF_X.at(1)] - 0.5).abs() < 1e-12);
        assert_eq!(r[0][0], 1.0);
        assert_eq!(r[0][1], 0.0);
        assert!(strong_pairs(&r, 25, 0.9).is_empty());
        assert_eq!(strong_pairs(&r, 25, 0.4).len(), 6);
    }
}
