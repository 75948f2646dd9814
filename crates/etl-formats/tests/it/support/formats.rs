//! Valid objects of every `etlcal.*` JSON format, generated through the formats' own types
//! (so that a new field or a new model family is one more line in its generator), and the
//! one interface the property tests drive them by: load, save, and the keys a file may
//! leave out (each read back as its documented default).

#![allow(dead_code)]

use std::fmt::Debug;
use std::path::{Path, PathBuf};

use etl_core::calib::params::MAX_PARAMS;
use etl_core::focus::FocusLaw;
use etl_core::model::{CameraModel, DistortionA, DistortionModel, FocalPoly};
use etl_core::thermal::{ThermalCalibration, ThermalSurface, E_IN_DOMAIN_MA, T_DOMAIN_C};
use etl_formats::calibration::{ModelStd, Outlier, ViewSummary};
use etl_formats::dataset::{Board, DatasetView, OffstateImage, SettingImage};
use etl_formats::observations::{OffstateView, PointObs, ViewObs, MAX_IMAGE_SIDE_PX};
use etl_formats::{A0File, Calibration, Dataset, Observations, Result, ThermalFile, ThermalRef};
use proptest::prelude::*;
use serde::Serialize;

/// A format the property tests know: how to generate a valid value, read and write it.
pub trait Format: Sized + Clone + Debug + PartialEq + Serialize {
    /// Its name in messages.
    const NAME: &'static str;
    /// Its `"format"` tag.
    const TAG: &'static str;
    /// The keys a file may leave out, as paths with `[]` for any index
    /// (`views[].e_com_ma`): each is read back as its documented default (absent, empty,
    /// zero). Any other dropped key must be an error naming it.
    const OPTIONAL: &'static [&'static str];
    /// Valid values.
    fn strategy() -> BoxedStrategy<Self>;
    /// The reader.
    fn load(path: &Path) -> Result<Self>;
    /// The writer.
    fn save(&self, path: &Path) -> Result<()>;
}

/// Any finite f64, of either sign and every magnitude (subnormals, 1e308, -0).
pub fn finite() -> BoxedStrategy<f64> {
    use proptest::num::f64::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
    (POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO).boxed()
}

/// A finite f64 >= 0.
fn non_negative() -> BoxedStrategy<f64> {
    finite().prop_map(f64::abs).boxed()
}

/// A [min, max] pair within `range`.
fn ordered(range: [f64; 2]) -> BoxedStrategy<[f64; 2]> {
    (range[0]..=range[1], range[0]..=range[1]).prop_map(|(a, b)| [a.min(b), a.max(b)]).boxed()
}

/// A [min, max] pair of any finite numbers.
fn ordered_any() -> BoxedStrategy<[f64; 2]> {
    (finite(), finite()).prop_map(|(a, b)| [a.min(b), a.max(b)]).boxed()
}

/// An image size within the documented limits (sides 1..65536, at most 2^28 px).
fn image_size() -> BoxedStrategy<[u32; 2]> {
    (1..=MAX_IMAGE_SIDE_PX, 1..=4096u32).prop_map(|(w, h)| [w, h]).boxed()
}

/// A camera model of either distortion family and any focal degree (1..=5): any finite
/// numbers.
fn camera_model() -> BoxedStrategy<CameraModel> {
    let v3 = || prop::array::uniform3(finite());
    let family = prop_oneof![Just(DistortionModel::Paper), Just(DistortionModel::OpenCv)];
    (family, 1..=5usize)
        .prop_flat_map(move |(family, degree)| {
            let poly = move || prop::collection::vec(finite(), degree + 1);
            (
                v3(),
                v3(),
                poly(),
                poly(),
                prop::array::uniform2(finite()),
                prop::collection::vec(finite(), family.a_len()),
            )
                .prop_map(move |(r, t, kx, ky, pp, a)| CameraModel {
                    rotation_rodrigues: r,
                    translation_mm: t,
                    kf_x: FocalPoly::new(&kx).unwrap(),
                    kf_y: FocalPoly::new(&ky).unwrap(),
                    principal_point: pp,
                    distortion_a: DistortionA::new(family, &a).unwrap(),
                    centre: None,
                })
        })
        .boxed()
}

/// A thermal calibration: any finite surface, ordered ranges.
fn thermal_calibration() -> BoxedStrategy<ThermalCalibration> {
    (prop::array::uniform10(finite()), ordered_any(), ordered_any())
        .prop_map(|(c, t, e)| ThermalCalibration {
            surface: ThermalSurface { coefficients: c },
            t_range_c: t,
            e_in_range_ma: e,
        })
        .boxed()
}

/// The thermal part of a calibration: whole, or (an older file) coefficients only.
fn thermal_ref() -> BoxedStrategy<ThermalRef> {
    (thermal_calibration(), non_negative(), "[ -~]{0,16}", any::<bool>())
        .prop_map(|(cal, rms, source, whole)| {
            let r = ThermalRef::from_file(&ThermalFile::new(&cal, rms), &source);
            if whole {
                r
            } else {
                ThermalRef { t_range_c: None, e_in_range_ma: None, rms_ma: None, source: None, ..r }
            }
        })
        .boxed()
}

/// A focus law, monotone over its range (c1, c2 >= 0 with c1 > 0: dE/dV > 0 for V > 0).
fn focus_law() -> BoxedStrategy<FocusLaw> {
    // The range is at most 40 times its near end wide, so that the widened range (2 % of
    // the width each side) stays in front of the camera.
    (-300.0..300.0, 0.1..100.0, 0.0..10.0, 1.0..500.0, 0.001..39.0, ordered(E_IN_DOMAIN_MA), 0.0..5.0, 0..100usize)
        .prop_map(|(c0, c1, c2, d0, width, e, rms, views)| FocusLaw {
            coefficients_ma: [c0, c1, c2],
            distance_range_mm: [d0, d0 * (1.0 + width)],
            e_com_range_ma: e,
            rms_ma: rms,
            views,
            setting: Default::default(),
        })
        .boxed()
}

/// A covariance the validator accepts: diagonal std^2, symmetric, |c_ij| <= s_i s_j.
fn covariance(std: [f64; MAX_PARAMS]) -> BoxedStrategy<[[f64; MAX_PARAMS]; MAX_PARAMS]> {
    prop::collection::vec(-1.0..=1.0f64, MAX_PARAMS * MAX_PARAMS)
        .prop_map(move |r| {
            core::array::from_fn(|i| {
                core::array::from_fn(|j| {
                    let rho = if i == j { 1.0 } else { r[i.min(j) * MAX_PARAMS + i.max(j)] };
                    rho * std[i] * std[j]
                })
            })
        })
        .boxed()
}

/// A per-view summary.
fn view_summary() -> BoxedStrategy<ViewSummary> {
    (finite(), 0..5000usize, non_negative(), finite(), finite(), finite(), finite())
        .prop_map(|(e, points, rms_px, dz_mm, de_ma, fx_px, fy_px)| ViewSummary {
            e_com_ma: e,
            focal_power_dpt: None,
            points,
            rms_px,
            dz_mm,
            de_ma,
            de_dpt: None,
            fx_px,
            fy_px,
        })
        .boxed()
}

/// Outliers naming views among `views` (at least one view when there are any).
fn outliers(views: usize) -> BoxedStrategy<Vec<Outlier>> {
    if views == 0 {
        return Just(vec![]).boxed();
    }
    prop::collection::vec((0..views, 0..5000usize, non_negative()), 0..4)
        .prop_map(|v| v.into_iter().map(|(view, point, residual_px)| Outlier { view, point, residual_px }).collect())
        .boxed()
}

impl Format for Calibration {
    const NAME: &'static str = "calibration";
    const TAG: &'static str = etl_formats::calibration::FORMAT;
    const OPTIONAL: &'static [&'static str] = &[
        "thermal",
        "thermal.t_range_c",
        "thermal.e_in_range_ma",
        "thermal.rms_ma",
        "thermal.source",
        "estimator",
        "iterations",
        "initial_rms_px",
        "views",
        "views[].fx_px",
        "views[].fy_px",
        "covariance",
        "focus_law",
        "outliers",
        "setting_outliers",
        "warnings",
    ];

    fn strategy() -> BoxedStrategy<Self> {
        let std =
            prop::collection::vec(0.0..1e3f64, MAX_PARAMS).prop_map(|v| <[f64; MAX_PARAMS]>::try_from(v).unwrap());
        let head = (camera_model(), image_size(), ordered(E_IN_DOMAIN_MA), non_negative(), std);
        let tail = (
            proptest::option::of(thermal_ref()),
            "[a-z-]{0,12}",
            0..1000usize,
            non_negative(),
            prop::collection::vec(view_summary(), 0..5),
            proptest::option::of(focus_law()),
            prop::collection::vec("[ -~]{0,40}", 0..3),
        );
        (head, tail)
            .prop_flat_map(
                |((model, size, range, rms, std), (thermal, estimator, iterations, initial, views, law, warnings))| {
                    let mut c = Calibration::from_model(&model, size, range);
                    c.rms_reprojection_px = rms;
                    c.std = ModelStd::from_params(&model.layout(), &std);
                    c.thermal = thermal;
                    c.estimator = estimator;
                    c.iterations = iterations;
                    c.initial_rms_px = initial;
                    c.focus_law = law;
                    c.warnings = warnings;
                    let n = views.len();
                    c.views = views;
                    (Just(c), proptest::option::of(covariance(std)), outliers(n), outliers(usize::MAX))
                },
            )
            .prop_map(|(mut c, cov, outliers, setting_outliers)| {
                if let Some(cov) = cov {
                    c.set_covariance(&cov).unwrap();
                }
                c.outliers = outliers;
                c.setting_outliers = setting_outliers;
                c
            })
            .boxed()
    }

    fn load(path: &Path) -> Result<Self> {
        Calibration::load(path)
    }

    fn save(&self, path: &Path) -> Result<()> {
        Calibration::save(self, path)
    }
}

/// A point of an image of `size` px: world within +-10 m (Z = 0 when `planar`), pixel within
/// the image and one image size around it.
fn point(size: [u32; 2], planar: bool) -> BoxedStrategy<PointObs> {
    let (w, h) = (f64::from(size[0]), f64::from(size[1]));
    let world = -10_000.0..=10_000.0f64;
    (world.clone(), world.clone(), world, -w..=2.0 * w, -h..=2.0 * h)
        .prop_map(move |(x, y, z, u, v)| PointObs { world_mm: [x, y, if planar { 0.0 } else { z }], pixel: [u, v] })
        .boxed()
}

/// A view of currents and temperature within the driver's domain.
fn view_obs(size: [u32; 2], planar: bool) -> BoxedStrategy<ViewObs> {
    let e = E_IN_DOMAIN_MA[0]..=E_IN_DOMAIN_MA[1];
    (
        e.clone(),
        T_DOMAIN_C[0]..=T_DOMAIN_C[1],
        proptest::option::of(e),
        prop::collection::vec(point(size, planar), 1..5),
    )
        .prop_map(|(e_in_ma, temperature_c, e_com_ma, points)| ViewObs {
            e_in_ma,
            focal_power_dpt: None,
            temperature_c,
            e_com_ma,
            points,
        })
        .boxed()
}

impl Format for Observations {
    const NAME: &'static str = "observations";
    const TAG: &'static str = etl_formats::observations::FORMAT;
    const OPTIONAL: &'static [&'static str] =
        &["views[].e_com_ma", "offstate_views", "setting_views", "setting_views[].e_com_ma"];

    fn strategy() -> BoxedStrategy<Self> {
        image_size()
            .prop_flat_map(|size| {
                let offstate =
                    prop::collection::vec(point(size, true), 1..5).prop_map(|points| OffstateView { points });
                (
                    Just(size),
                    prop::collection::vec(view_obs(size, false), 1..4),
                    prop::collection::vec(offstate, 0..3),
                    prop::collection::vec(view_obs(size, true), 0..3),
                )
            })
            .prop_map(|(size, views, offstate_views, setting_views)| Observations {
                views,
                offstate_views,
                setting_views,
                ..Observations::new(size)
            })
            .boxed()
    }

    fn load(path: &Path) -> Result<Self> {
        Observations::load(path)
    }

    fn save(&self, path: &Path) -> Result<()> {
        Observations::save(self, path)
    }
}

/// A board the validator accepts: a checkerboard, or a ChArUco board of any of OpenCV's
/// dictionaries with enough markers.
pub fn board() -> BoxedStrategy<Board> {
    let checkerboard = (3..100usize, 3..100usize, finite().prop_filter("a positive square", |s| *s > 0.0))
        .prop_filter_map("a pattern of finite size", |(c, r, square_mm)| Board::checkerboard([c, r], square_mm).ok());
    let names: Vec<&'static str> = etl_core::board::Dictionary::all().iter().map(|d| d.name()).collect();
    let charuco = (
        2..40u32,
        2..40u32,
        finite().prop_filter("a positive square", |s| *s > 0.0),
        0.05..0.95f64,
        prop::sample::select(names),
    )
        .prop_filter_map("a dictionary with enough markers", |(c, r, square_mm, f, name)| {
            Board::charuco([c, r], square_mm, square_mm * f, name).ok()
        });
    prop_oneof![checkerboard, charuco].boxed()
}

/// An image path (any text: the dataset keeps it as written).
fn image_path() -> BoxedStrategy<PathBuf> {
    "[ -~]{1,24}".prop_map(PathBuf::from).boxed()
}

fn first_corner() -> BoxedStrategy<Option<[usize; 2]>> {
    proptest::option::of(prop::array::uniform2(0..1000usize)).boxed()
}

impl Format for Dataset {
    const NAME: &'static str = "dataset";
    const TAG: &'static str = etl_formats::dataset::FORMAT;
    const OPTIONAL: &'static [&'static str] = &[
        "views",
        "views[].e_com_ma",
        "views[].board",
        "views[].first_corner",
        "offstate_board",
        "offstate_views",
        "offstate_views[].board",
        "offstate_views[].first_corner",
        "setting_views",
        "setting_views[].e_com_ma",
        "setting_views[].board",
        "setting_views[].first_corner",
        // A board object inline: its format tag may be left out, and without a type it is
        // a checkerboard (the dataset's board object of before the board format).
        "board.format",
        "board.type",
        "views[].board.format",
        "views[].board.type",
        "offstate_board.format",
        "offstate_board.type",
        "offstate_views[].board.format",
        "offstate_views[].board.type",
        "setting_views[].board.format",
        "setting_views[].board.type",
    ];

    fn strategy() -> BoxedStrategy<Self> {
        let view = (
            image_path(),
            finite(),
            finite(),
            proptest::option::of(finite()),
            finite(),
            proptest::option::of(board()),
            first_corner(),
        )
            .prop_map(|(image, e_in_ma, temperature_c, e_com_ma, z_w_mm, board, first_corner)| DatasetView {
                image,
                e_in_ma,
                focal_power_dpt: None,
                temperature_c,
                e_com_ma,
                z_w_mm,
                board,
                first_corner,
            });
        let offstate = (image_path(), proptest::option::of(board()), first_corner())
            .prop_map(|(image, board, first_corner)| OffstateImage { image, board, first_corner });
        let setting = (
            image_path(),
            finite(),
            finite(),
            proptest::option::of(finite()),
            proptest::option::of(board()),
            first_corner(),
        )
            .prop_map(|(image, e_in_ma, temperature_c, e_com_ma, board, first_corner)| SettingImage {
                image,
                e_in_ma,
                focal_power_dpt: None,
                temperature_c,
                e_com_ma,
                board,
                first_corner,
            });
        (
            (1..=u32::MAX, 1..=u32::MAX),
            board(),
            prop::collection::vec(view, 1..4),
            proptest::option::of(board()),
            prop::collection::vec(offstate, 0..3),
            prop::collection::vec(setting, 0..3),
        )
            .prop_map(|((w, h), board, views, offstate_board, offstate_views, setting_views)| {
                let mut d =
                    Dataset { views, offstate_board, offstate_views, setting_views, ..Dataset::new([w, h], board) };
                // `first_corner` places a checkerboard's sub-board: none with a ChArUco board.
                let charuco = |b: Option<Board>, default: Board| matches!(b.unwrap_or(default), Board::Charuco(_));
                let (main, off) = (d.board, d.offstate_board());
                for v in &mut d.views {
                    if charuco(v.board, main) {
                        v.first_corner = None;
                    }
                }
                for v in &mut d.offstate_views {
                    if charuco(v.board, off) {
                        v.first_corner = None;
                    }
                }
                for v in &mut d.setting_views {
                    if charuco(v.board, main) {
                        v.first_corner = None;
                    }
                }
                d
            })
            .boxed()
    }

    fn load(path: &Path) -> Result<Self> {
        Dataset::load(path)
    }

    fn save(&self, path: &Path) -> Result<()> {
        Dataset::save(self, path)
    }
}

impl Format for A0File {
    const NAME: &'static str = "a0";
    const TAG: &'static str = etl_formats::a0::FORMAT;
    const OPTIONAL: &'static [&'static str] = &[];

    fn strategy() -> BoxedStrategy<Self> {
        let positive = || finite().prop_filter("positive", |x| *x > 0.0);
        (positive(), positive(), finite(), finite())
            .prop_map(|(kf0x, kf0y, u0, v0)| A0File::new(&etl_core::calib::A0 { kf0x, kf0y, u0, v0 }))
            .boxed()
    }

    fn load(path: &Path) -> Result<Self> {
        A0File::load(path)
    }

    fn save(&self, path: &Path) -> Result<()> {
        A0File::save(self, path)
    }
}

impl Format for ThermalFile {
    const NAME: &'static str = "thermal";
    const TAG: &'static str = etl_formats::thermal::THERMAL_FORMAT;
    const OPTIONAL: &'static [&'static str] = &[];

    fn strategy() -> BoxedStrategy<Self> {
        (thermal_calibration(), non_negative()).prop_map(|(cal, rms)| ThermalFile::new(&cal, rms)).boxed()
    }

    fn load(path: &Path) -> Result<Self> {
        ThermalFile::load(path)
    }

    fn save(&self, path: &Path) -> Result<()> {
        ThermalFile::save(self, path)
    }
}

/// The `etlcal.board/1` file: the same boards a dataset holds inline, as files of their own.
impl Format for Board {
    const NAME: &'static str = "board";
    const TAG: &'static str = etl_formats::board::FORMAT;
    // A checkerboard written without "type", as before boards had types, is read as one.
    const OPTIONAL: &'static [&'static str] = &["type"];

    fn strategy() -> BoxedStrategy<Self> {
        board()
    }

    fn load(path: &Path) -> Result<Self> {
        Board::load(path)
    }

    fn save(&self, path: &Path) -> Result<()> {
        Board::save(self, path)
    }
}
