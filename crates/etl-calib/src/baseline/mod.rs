//! The baseline of the paper's section 5.2.3 (the "existing method"): a monofocal Zhang
//! calibration at each current separately, then a cubic through fx(E) and fy(E).
//!
//! Input: the observations' `setting_views` (a planar board in a free pose per view,
//! several views per current). Views whose E_com agree within
//! [`SETTING_TOLERANCE_MA`] form one setting; each setting needs at least 3 views (Zhang)
//! and the baseline at least 3 settings (a curve through fewer is not a calibration over
//! current). The curve is a least-squares polynomial of degree min(3, settings - 1),
//! weighted by each setting's standard deviation; (u0, v0) is the weighted mean of the
//! settings'; k1, p1, p2 are fitted as quadratics in w = 1 / f_mean (Eq. 18) to give
//! a1..a9. R and T are not defined by this method (no common world frame) and are written
//! as zero: the result serves measurements (PnP), not stage geometry.

use etl_core::linalg::svd::sym_pinv;

use crate::zhang::{zhang, PlanarView, ZhangResult};
use etl_formats::calibration::{
    Calibration, ModelStd, Outlier, TemperatureCompensation, ThermalRef, ViewSummary, FORMAT,
};
use etl_formats::observations::{Observations, SETTING_TOLERANCE_MA};
use etl_formats::{Error, Result};

/// One setting's Zhang calibration.
#[derive(Debug, Clone)]
pub struct SettingEstimate {
    /// Mean E_com of the setting's views, mA.
    pub e_com_ma: f64,
    /// Views in the setting.
    pub views: usize,
    /// Points in the setting.
    pub points: usize,
    /// Zhang's result at this setting (its outliers index this setting's views).
    pub zhang: ZhangResult,
    /// The index in the observations' `setting_views` of each of this setting's views, in
    /// the order Zhang's method took them.
    pub setting_views: Vec<usize>,
}

/// The baseline's result: every setting and the calibration file it gives.
#[derive(Debug, Clone)]
pub struct BaselineResult {
    /// Per setting, sorted by current.
    pub settings: Vec<SettingEstimate>,
    /// What `etlcal calibrate --method per-setting` writes (`estimator` = "per-setting").
    pub calibration: Calibration,
}

/// Weighted least squares of a polynomial of degree `deg` (<= 3) in t = (x - c) / h,
/// returning raw monomial coefficients and their covariance.
fn poly_fit(x: &[f64], y: &[f64], sd: &[f64], deg: usize) -> Result<([f64; 4], [[f64; 4]; 4])> {
    let lo = x.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (c, h) = ((hi + lo) / 2.0, ((hi - lo) / 2.0).max(1e-300));
    let mut ata = [[0.0; 4]; 4];
    let mut aty = [0.0; 4];
    for ((&xi, &yi), &si) in x.iter().zip(y).zip(sd) {
        let t = (xi - c) / h;
        let w = 1.0 / (si * si).max(1e-300);
        let row: [f64; 4] = core::array::from_fn(|k| if k <= deg { t.powi(k as i32) } else { 0.0 });
        for i in 0..4 {
            aty[i] += w * row[i] * yi;
            for j in 0..4 {
                ata[i][j] += w * row[i] * row[j];
            }
        }
    }
    let (inv, rank) = sym_pinv(&ata, 1e-12);
    if rank < deg + 1 {
        return Err(Error::Core(etl_core::Error::Degenerate { what: "per-setting curve fit is rank deficient" }));
    }
    let ct: [f64; 4] = core::array::from_fn(|i| (0..4).map(|j| inv[i][j] * aty[j]).sum());
    // t^k = ((x - c) / h)^k expanded: raw = M ct with M[i][k] = C(k, i) (-c)^(k-i) / h^k.
    let binom = |n: usize, k: usize| -> f64 { (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64) };
    let mut m = [[0.0; 4]; 4];
    for k in 0..4 {
        for i in 0..=k {
            m[i][k] = binom(k, i) * (-c).powi((k - i) as i32) / h.powi(k as i32);
        }
    }
    let raw: [f64; 4] = core::array::from_fn(|i| (0..4).map(|k| m[i][k] * ct[k]).sum());
    let mut cov = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            cov[i][j] = (0..4).map(|a| (0..4).map(|b| m[i][a] * inv[a][b] * m[j][b]).sum::<f64>()).sum();
        }
    }
    // The settings' own scatter, when larger than their stated std, widens the result.
    let n = x.len();
    if n > deg + 1 {
        let chi2: f64 = x
            .iter()
            .zip(y)
            .zip(sd)
            .map(|((&xi, &yi), &si)| {
                let f = raw[0] + raw[1] * xi + raw[2] * xi * xi + raw[3] * xi * xi * xi;
                ((yi - f) / si).powi(2)
            })
            .sum();
        let scale = (chi2 / (n - deg - 1) as f64).max(1.0);
        cov.iter_mut().flatten().for_each(|v| *v *= scale);
    }
    Ok((raw, cov))
}

/// Runs the baseline on `obs.setting_views` (see the module docs).
///
/// Errors: no setting views; a setting with fewer than 3 views; fewer than 3 settings;
/// Zhang's errors at a setting (named with its current).
pub fn per_setting(obs: &Observations, thermal: Option<&ThermalRef>) -> Result<BaselineResult> {
    let settings = setting_estimates(obs, thermal)?;
    let calibration = calibration_of(&settings, obs.image_size, thermal)?;
    Ok(BaselineResult { settings, calibration })
}

/// Zhang's method at each setting of `obs.setting_views`: views grouped by E_com (within
/// `SETTING_TOLERANCE_MA`), sorted by E_com; at least 3 settings of at least 3 views each.
fn setting_estimates(obs: &Observations, thermal: Option<&ThermalRef>) -> Result<Vec<SettingEstimate>> {
    obs.validate()?;
    if obs.setting_views.is_empty() {
        return Err(Error::invalid(
            "setting_views",
            "--method per-setting needs setting_views (several board views at each current)",
        ));
    }
    let e_com = obs.setting_e_com_ma(thermal)?;
    let mut order: Vec<usize> = (0..e_com.len()).collect();
    order.sort_by(|&a, &b| e_com[a].total_cmp(&e_com[b]));
    let mut groups: Vec<Vec<usize>> = vec![];
    for i in order {
        match groups.last_mut() {
            Some(g) if (e_com[i] - e_com[g[0]]).abs() < SETTING_TOLERANCE_MA => g.push(i),
            _ => groups.push(vec![i]),
        }
    }
    if groups.len() < 3 {
        return Err(Error::invalid(
            "setting_views",
            format!("the per-setting baseline needs views at >= 3 distinct currents, got {}", groups.len()),
        ));
    }
    let mut settings = vec![];
    for g in &groups {
        let e = g.iter().map(|&i| e_com[i]).sum::<f64>() / g.len() as f64;
        if g.len() < 3 {
            return Err(Error::invalid(
                "setting_views",
                format!("the setting at {e:.1} mA has {} views; Zhang's method needs at least 3", g.len()),
            ));
        }
        let views: Vec<PlanarView> = g
            .iter()
            .map(|&i| PlanarView {
                board_mm: obs.setting_views[i].points.iter().map(|p| [p.world_mm[0], p.world_mm[1]]).collect(),
                pixels: obs.setting_views[i].points.iter().map(|p| p.pixel).collect(),
            })
            .collect();
        let z = zhang(&views, obs.image_size).map_err(|err| {
            match crate::zhang::in_list(err, "setting_views", Some(g)) {
                Error::InvalidInput { what, value, message } => {
                    Error::InvalidInput { what, value, message: format!("setting at {e:.1} mA: {message}") }
                }
                other => other,
            }
        })?;
        let points = views.iter().map(|v| v.pixels.len()).sum();
        settings.push(SettingEstimate { e_com_ma: e, views: g.len(), points, zhang: z, setting_views: g.clone() });
    }
    Ok(settings)
}

/// Zhang's outliers of every setting, their views mapped to the observations'
/// `setting_views` (sorted by view and point).
fn setting_outliers(settings: &[SettingEstimate]) -> Vec<Outlier> {
    let mut all: Vec<Outlier> = settings
        .iter()
        .flat_map(|s| {
            s.zhang.outliers.iter().filter_map(|o| Some(Outlier { view: *s.setting_views.get(o.view)?, ..*o }))
        })
        .collect();
    all.sort_by_key(|o| (o.view, o.point));
    all
}

/// Eq. 18: k1, p1, p2 of the per-setting estimates as quadratics in w = 1 / f_mean,
/// weighted by their stds; returns a_1..a_9 and their stds.
fn distortion_a_of(settings: &[SettingEstimate]) -> Result<([f64; 9], [f64; 9])> {
    let ws: Vec<f64> = settings.iter().map(|s| 2.0 / (s.zhang.fx + s.zhang.fy)).collect();
    let mut a = [0.0; 9];
    let mut sa = [0.0; 9];
    for (k, idx) in [4usize, 5, 6].into_iter().enumerate() {
        let (y, sd): (Vec<f64>, Vec<f64>) =
            settings.iter().map(|s| (s.zhang.coefficients[k], s.zhang.std[idx].max(1e-12))).unzip();
        let (c, cov) = poly_fit(&ws, &y, &sd, 2)?;
        // Eq. 18 order: a_(3k+1) w^2 + a_(3k+2) w + a_(3k+3).
        a[3 * k] = c[2];
        a[3 * k + 1] = c[1];
        a[3 * k + 2] = c[0];
        sa[3 * k] = cov[2][2].max(0.0).sqrt();
        sa[3 * k + 1] = cov[1][1].max(0.0).sqrt();
        sa[3 * k + 2] = cov[0][0].max(0.0).sqrt();
    }
    Ok((a, sa))
}

/// The calibration the per-setting estimates give: fx, fy as weighted polynomials of
/// E_com (cubic, or of degree settings - 1), (u0, v0) as weighted means, k1, p1, p2 as
/// quadratics in w = 1 / f_mean (Eq. 18). Precondition: `settings` sorted by E_com, not
/// empty.
fn calibration_of(
    settings: &[SettingEstimate],
    image_size: [u32; 2],
    thermal: Option<&ThermalRef>,
) -> Result<Calibration> {
    let es: Vec<f64> = settings.iter().map(|s| s.e_com_ma).collect();
    let deg = 3.min(settings.len() - 1);
    let col = |f: &dyn Fn(&ZhangResult) -> (f64, f64)| -> (Vec<f64>, Vec<f64>) {
        settings.iter().map(|s| f(&s.zhang)).map(|(v, sd)| (v, sd.max(1e-12))).unzip()
    };
    let (fx, sfx) = col(&|z| (z.fx, z.std[0]));
    let (fy, sfy) = col(&|z| (z.fy, z.std[1]));
    let (kf_x, cx) = poly_fit(&es, &fx, &sfx, deg)?;
    let (kf_y, cy) = poly_fit(&es, &fy, &sfy, deg)?;
    let wmean = |f: &dyn Fn(&ZhangResult) -> (f64, f64)| {
        let (mut s, mut w) = (0.0, 0.0);
        for st in settings {
            let (v, sd) = f(&st.zhang);
            let wi = 1.0 / (sd * sd).max(1e-300);
            s += wi * v;
            w += wi;
        }
        (s / w, (1.0 / w).sqrt())
    };
    let (u0, su0) = wmean(&|z| (z.u0, z.std[2]));
    let (v0, sv0) = wmean(&|z| (z.v0, z.std[3]));
    let (a, sa) = distortion_a_of(settings)?;
    let sd4 = |c: &[[f64; 4]; 4]| -> [f64; 4] { core::array::from_fn(|i| c[i][i].max(0.0).sqrt()) };
    let n_points: usize = settings.iter().map(|s| s.points).sum();
    let rms = (settings.iter().map(|s| s.zhang.rms_px.powi(2) * s.points as f64).sum::<f64>() / n_points.max(1) as f64)
        .sqrt();
    let calibration = Calibration {
        format: FORMAT.into(),
        image_size,
        rotation_rodrigues: [0.0; 3],
        translation_mm: [0.0; 3],
        kf_x: kf_x.to_vec(),
        kf_y: kf_y.to_vec(),
        principal_point: [u0, v0],
        distortion_model: None,
        distortion_a: a.to_vec(),
        // The baseline's principal point is the weighted mean of the settings' (fixed).
        centre: None,
        thermal: thermal.cloned(),
        temperature_compensation: TemperatureCompensation::of(thermal),
        setting: None,
        e_com_range_ma: [es[0], es[es.len() - 1]],
        focal_power_range_dpt: None,
        focal_power_t_range_c: None,
        rms_reprojection_px: rms,
        std: ModelStd {
            rotation_rodrigues: [0.0; 3],
            translation_mm: [0.0; 3],
            kf_x: sd4(&cx).to_vec(),
            kf_y: sd4(&cy).to_vec(),
            principal_point: [su0, sv0],
            distortion_a: sa.to_vec(),
            centre: None,
        },
        estimator: "per-setting".into(),
        // Zhang's per-setting solves set their own outliers aside (crate::zhang); they are
        // corners of setting views, not of the observations' ETL views that `outliers` names.
        outliers: vec![],
        setting_outliers: setting_outliers(settings),
        // Each setting is its own camera here, not a setting view posed beside the stage
        // views of one model.
        setting_views: vec![],
        warnings: vec![],
        // No joint covariance: kf_x, kf_y, (u0, v0) and each a-triple come from separate
        // fits whose cross-covariances are not computed; a block-diagonal matrix would
        // claim independence it does not have. Downstream uncertainty is refused instead.
        covariance: None,
        covariance_noise: None,
        iterations: settings.iter().map(|s| s.zhang.iterations).max().unwrap_or(0),
        initial_rms_px: rms,
        // Each setting's boards are in their own frames and the calibration has no pose:
        // there is no distance to fit a focus law to.
        focus_law: None,
        model_selection: None,
        views: settings
            .iter()
            .map(|s| ViewSummary {
                e_com_ma: s.e_com_ma,
                focal_power_dpt: None,
                points: s.points,
                rms_px: s.zhang.rms_px,
                dz_mm: 0.0,
                de_ma: 0.0,
                de_dpt: None,
                fx_px: s.zhang.fx,
                fy_px: s.zhang.fy,
            })
            .collect(),
    };
    Ok(calibration)
}
