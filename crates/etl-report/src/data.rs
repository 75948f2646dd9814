//! What a report shows, gathered from a calibration (and its observations): the views'
//! residuals and own estimates, the projection-uncertainty maps, the figures' list and the
//! provenance. The drawing ([`crate::plots`]) and the page ([`crate::html`]) read it; the
//! writer ([`crate::write_report`]) puts them together.

use etl_core::calib::distortion_init::view_distortion;
use etl_core::calib::params::MAX_PARAMS;
use etl_core::calib::{projection_uncertainty, View};
use etl_core::model::CameraModel;
use etl_formats::calibration::{Calibration, ThermalRef};
use etl_formats::observations::Observations;
use etl_formats::Result;

/// Where a report's calibration came from, for its provenance section (the calibration
/// file itself records the estimator and the thermal calibration, not the inputs or the
/// estimator's priors).
#[derive(Debug, Clone, Default)]
pub struct Provenance {
    /// The inputs, each as (role, where): ("calibration", "out/calibration.json").
    pub inputs: Vec<(String, String)>,
    /// The estimator's priors in words; `None`: not known to the caller (the report says
    /// so rather than guess).
    pub priors: Option<String>,
    /// When the report was written, seconds since 1970-01-01 UTC; `None`: the system clock
    /// now. Callers pass a fixed time for reports that must be reproducible byte for byte
    /// (`etlcal` takes it from `SOURCE_DATE_EPOCH`, reproducible-builds.org's convention).
    pub written_unix_s: Option<i64>,
}

impl Provenance {
    /// The priors of `estimator` in words (for callers that ran the calibration).
    pub fn priors_of(estimator: &etl_core::calib::Estimator) -> String {
        match estimator {
            etl_core::calib::Estimator::Paper => {
                "none in the fit: the paper's estimator takes the recorded stage positions and currents as exact \
                 (its covariance accounts for their errors: see covariance)"
                    .into()
            }
            etl_core::calib::Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px } => format!(
                "errors-in-variables: stage position std {:.1} um, current std {sigma_e_ma} mA, pixel noise {}",
                sigma_z_mm * 1000.0,
                sigma_px.map_or("estimated from the data".to_string(), |s| format!("{s} px"))
            ),
        }
    }
}

/// The figures a report can hold, as (file stem, heading); each is written as
/// `stem.svg` and `stem.png`. Those needing observations are left out without them.
pub const REPORT_FIGURES: [(&str, &str); 9] = [
    ("focal", "Focal lengths against the current"),
    ("distortion", "Distortion coefficients against the current"),
    ("projection_std", "Projection uncertainty over the image"),
    ("coverage", "Coverage: where the corners were, per current"),
    ("residual_map", "Residual vectors, coloured by view"),
    ("view_rms", "RMS residual per view"),
    ("residual_hist", "Histogram of the residuals"),
    ("distortion_field", "Distortion field at three currents"),
    ("correlation", "Correlation matrix of the model's numbers"),
];

/// One residual: where (observed pixel) and the residual (model - observed), px.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Residual {
    pub at: [f64; 2],
    pub d: [f64; 2],
}

/// One view as the figures need it.
pub(crate) struct ViewData {
    /// E_com with the view's current correction, mA.
    pub e_com_ma: f64,
    /// Observed pixels.
    pub pixels: Vec<[f64; 2]>,
    /// Residuals (empty for the per-setting baseline, which has no stage frame).
    pub residuals: Vec<Residual>,
    /// Mean camera-frame depth of the view's points, mm.
    pub depth_mm: f64,
}

/// The projection-uncertainty map at one current.
pub(crate) struct StdMap {
    pub e_com_ma: f64,
    /// The depth of the points, mm, along the optical axis.
    pub depth_mm: f64,
    /// Cells (rows top to bottom, columns left to right): worst-direction std, px.
    pub cells: Vec<Vec<f64>>,
}

pub(crate) struct Data {
    pub cal: Calibration,
    pub model: CameraModel,
    pub covariance: Option<[[f64; MAX_PARAMS]; MAX_PARAMS]>,
    /// (E, fx, fy) of every view's own estimate (0: none).
    pub view_focal: Vec<(f64, f64, f64)>,
    /// (E, k1, p1, p2) of every view's own estimate.
    pub view_dist: Vec<(f64, [f64; etl_core::model::MAX_COEFFICIENTS])>,
    pub views: Vec<ViewData>,
    /// The three currents the maps are drawn at: the ends and the middle of the range.
    pub map_currents: [f64; 3],
    pub std_maps: Vec<StdMap>,
    /// How the depth of the projection-uncertainty map was chosen.
    pub depth_source: &'static str,
}

impl Data {
    pub fn residual_count(&self) -> usize {
        self.views.iter().map(|v| v.residuals.len()).sum()
    }
}

/// The view summaries' own estimates, or (when the file has none) each view's fx, fy
/// refitted to that view alone ([`etl_calib::pipeline::view_focal`]).
fn gather_views(
    cal: &Calibration,
    model: &CameraModel,
    obs: &Observations,
    thermal: Option<&ThermalRef>,
) -> Result<Data> {
    obs.validate()?;
    let e_com = obs.e_com_ma(thermal)?;
    let pts = obs.core_points();
    let mut view_focal: Vec<(f64, f64, f64)> = cal.views.iter().map(|v| (v.setting(), v.fx_px, v.fy_px)).collect();
    let recompute = view_focal.len() != obs.views.len() || view_focal.iter().all(|v| v.1 == 0.0);
    if recompute {
        view_focal.clear();
    }
    // The per-setting baseline has no stage frame (R, T): its views cannot be reprojected.
    let frame = cal.estimator != "per-setting";
    let (mut view_dist, mut views) = (vec![], vec![]);
    for (k, (p, &e)) in pts.iter().zip(&e_com).enumerate() {
        // The errors-in-variables corrections of the calibration, when it has them.
        let (dz, de) = cal.views.get(k).map_or((0.0, 0.0), |v| (v.dz_mm, v.setting_correction()));
        // The points of the final solve: the calibration's outliers (listed in their own
        // table) would swamp the residual plots and the view's distortion estimate.
        let outlier = |i: usize| cal.outliers.iter().any(|o| o.view == k && o.point == i);
        let shifted: Vec<etl_core::calib::Point> = p
            .iter()
            .enumerate()
            .filter(|(i, _)| !outlier(*i))
            .map(|(_, q)| etl_core::calib::Point {
                world_mm: [q.world_mm[0], q.world_mm[1], q.world_mm[2] + dz],
                pixel: q.pixel,
            })
            .collect();
        let e = e + de;
        let mut v = ViewData {
            e_com_ma: e,
            pixels: p.iter().map(|q| q.pixel).collect(),
            residuals: vec![],
            depth_mm: f64::NAN,
        };
        if frame {
            if recompute {
                let (fx, fy) = etl_calib::pipeline::view_focal(model, &View { e_com_ma: e - de, points: p }, dz)
                    .unwrap_or((0.0, 0.0));
                view_focal.push((e, fx, fy));
            }
            if let Ok(dd) = view_distortion(model, &View { e_com_ma: e, points: &shifted }) {
                view_dist.push((e, *dd.padded()));
            }
            for q in &shifted {
                if let Ok(m) = model.project(q.world_mm, e) {
                    v.residuals.push(Residual { at: q.pixel, d: [m[0] - q.pixel[0], m[1] - q.pixel[1]] });
                }
            }
            let z: Vec<f64> = shifted.iter().map(|q| model.world_to_camera(q.world_mm)[2]).collect();
            v.depth_mm = z.iter().sum::<f64>() / z.len().max(1) as f64;
        }
        views.push(v);
    }
    Ok(Data {
        cal: cal.clone(),
        model: *model,
        covariance: None,
        view_focal,
        view_dist,
        views,
        map_currents: [0.0; 3],
        std_maps: vec![],
        depth_source: "",
    })
}

/// Worst-direction std of a 2 x 2 covariance: sqrt of its largest eigenvalue.
fn worst_std(c: &[[f64; 2]; 2]) -> f64 {
    let (m, d) = (0.5 * (c[0][0] + c[1][1]), 0.5 * (c[0][0] - c[1][1]));
    (m + (d * d + c[0][1] * c[0][1]).sqrt()).max(0.0).sqrt()
}

/// The depth the map's points are at, at `e_com_ma`, and how it was chosen: the focus
/// law's distance in focus; else the mean depth of the view nearest in current; else the
/// depth of the world origin.
fn map_depth(d: &Data, e_com_ma: f64) -> (f64, &'static str) {
    if let Some(z) = d.cal.focus_law.as_ref().and_then(|f| f.distance_mm(e_com_ma).ok()) {
        return (z, "the distance in focus at that current (the calibration's focus law)");
    }
    let nearest = d
        .views
        .iter()
        .filter(|v| v.depth_mm.is_finite())
        .min_by(|a, b| (a.e_com_ma - e_com_ma).abs().total_cmp(&(b.e_com_ma - e_com_ma).abs()));
    if let Some(v) = nearest {
        return (v.depth_mm, "the mean depth of the corners of the view nearest in current (no focus law)");
    }
    (d.model.translation_mm[2], "the depth of the world origin (no focus law and no observations)")
}

/// Cells of the projection-uncertainty map (columns x rows over the image).
const MAP_CELLS: (usize, usize) = (32, 24);

fn std_map(d: &Data, c: &[[f64; MAX_PARAMS]; MAX_PARAMS], e_com_ma: f64) -> StdMap {
    let (depth_mm, _) = map_depth(d, e_com_ma);
    let [w, h] = d.cal.image_size;
    let cells = (0..MAP_CELLS.1)
        .map(|r| {
            (0..MAP_CELLS.0)
                .map(|k| {
                    let px = [
                        (k as f64 + 0.5) * w as f64 / MAP_CELLS.0 as f64,
                        (r as f64 + 0.5) * h as f64 / MAP_CELLS.1 as f64,
                    ];
                    // The world point on the pixel's ray at the chosen depth (camera z).
                    let Ok(ray) = d.model.ray(px, e_com_ma) else { return f64::NAN };
                    let z1 = d.model.world_to_camera(ray.at(1.0))[2] - d.model.world_to_camera(ray.origin_mm)[2];
                    projection_uncertainty(&d.model, c, ray.at(depth_mm / z1), e_com_ma)
                        .map_or(f64::NAN, |u| worst_std(&u.covariance_px2))
                })
                .collect()
        })
        .collect();
    StdMap { e_com_ma, depth_mm, cells }
}

pub(crate) fn gather(cal: &Calibration, obs: Option<&Observations>, thermal: Option<&ThermalRef>) -> Result<Data> {
    let model = cal.model()?;
    let mut d = match obs {
        Some(obs) => gather_views(cal, &model, obs, thermal)?,
        None => Data {
            cal: cal.clone(),
            model,
            covariance: None,
            view_focal: cal.views.iter().map(|v| (v.setting(), v.fx_px, v.fy_px)).collect(),
            view_dist: vec![],
            views: vec![],
            map_currents: [0.0; 3],
            std_maps: vec![],
            depth_source: "",
        },
    };
    let r = cal.setting_range();
    d.map_currents = [r[0], 0.5 * (r[0] + r[1]), r[1]];
    d.covariance = cal.covariance_matrix();
    d.depth_source = map_depth(&d, d.map_currents[1]).1;
    if let Some(c) = d.covariance {
        d.std_maps = d.map_currents.iter().map(|&e| std_map(&d, &c, e)).collect();
    }
    Ok(d)
}

/// The name and unit of a calibration's setting as the report labels it: ("E_com", "mA"),
/// or ("focal power", "dpt") for a focal-power calibration.
pub(crate) fn setting_axis(cal: &etl_formats::Calibration) -> (&'static str, &'static str) {
    match cal.setting_kind() {
        etl_formats::SettingKind::Current => ("E_com", "mA"),
        etl_formats::SettingKind::FocalPower => ("focal power", "dpt"),
    }
}
