//! `etlcal stereo LEFT... --right RIGHT... (--pattern CxR --square MM | --board FILE)
//! --model paper|opencv [--fix-k3] [--zero-tangent] [--intrinsics fixed|joint] [--json]`:
//! a fixed-focus camera pair from synchronised images of a board (`etl_calib::stereo`).
//!
//! LEFT and RIGHT are paired by position (the k-th left image with the k-th right one).
//! The board is detected in every image; an image where it is not found is named on
//! stderr and its pair is used by the other camera's own calibration only. Each camera is
//! calibrated by Zhang's method on every image it saw the board in (as `etlcal zhang`,
//! whose `--model`, `--fix-k3`, `--zero-tangent` these are), then the relative pose R, T
//! over the pairs seen by both, as `cv2.stereoCalibrate`: with `--intrinsics fixed` (the
//! default, OpenCV's `CALIB_FIX_INTRINSIC` after `calibrateCamera`) the intrinsics are
//! held, with `--intrinsics joint` both cameras' are refined with R, T over the pairs
//! (OpenCV's flags 0).
//!
//! `--json` prints `{"left", "right", "rotation_rodrigues", "translation_mm", "rms_px",
//! "views_used", "rotation_matrix", "baseline_mm", "std": {"rotation_rodrigues",
//! "translation_mm"}, "per_view_rms_px": [[left, right], ...], "pairs_used", "model",
//! "intrinsics"}`: `left` and `right` hold exactly the keys of `etlcal zhang --json`
//! (their `view` indices, images and `views_used` those of that camera's images; in the
//! joint mode the numbers, `std` and RMS of the joint fit over the pairs, and
//! `projection_std_px` null throughout: the single camera's projection uncertainty does
//! not apply to a joint fit); X_r = R X_l + T takes a point from the left camera's frame
//! to the right's (`cv2.stereoCalibrate`'s R, T; `rotation_rodrigues` is R as a Rodrigues
//! vector); `rms_px` is the RMS reprojection distance over both cameras' corners of the
//! pairs used (`cv2.stereoCalibrate`'s return value); `views_used` counts those pairs and
//! `pairs_used` lists their indices; `std` is one standard deviation of R and T (with
//! the intrinsics held, their own uncertainty carried through).
//!
//! `--opencv-yaml FILE` (with `--model opencv`) also writes the pair as OpenCV FileStorage
//! YAML, `cv2.FileStorage` readable: `image_width`, `image_height`, `K1`, `D1`, `K2`, `D2`,
//! `R`, `T`, Bouguet's rectification `R1`, `R2`, `P1`, `P2`, `Q` as `cv2.stereoRectify`
//! returns them with its defaults (`etl_calib::stereo::rectify`), and `rms_px`; `--json`
//! then adds `"opencv_yaml"`, the path written.

use std::path::PathBuf;

use serde_json::{json, Value};

use super::print_json;
use crate::board::BoardArgs;
use crate::calibrate::FlagSpelling;
use crate::zhang::{result_json, ModelArg};
use etl_calib::pipeline::{detect_views, PlanarViews};
use etl_calib::request::ZhangRequest;
use etl_calib::stereo::{rectify, stereo_calibrate, StereoMode, StereoOptions, StereoPair, StereoResult};
use etl_calib::zhang::ZhangOptions;
use etl_core::model::{DistortionModel, OpenCvFlags};
use etl_formats::board::Board;
use etl_formats::export::stereo::{opencv_stereo_yaml, OpenCvCamera, OpenCvStereo};
use etl_formats::output::Output;
use etl_formats::{write_atomic, Error, Result};

/// What `--intrinsics` holds or frees.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntrinsicsArg {
    /// Each camera's intrinsics from its own Zhang calibration, held while R, T are fitted
    /// (cv2.stereoCalibrate with CALIB_FIX_INTRINSIC after calibrateCamera).
    Fixed,
    /// Both cameras' intrinsics refined with R, T over the pairs seen by both
    /// (cv2.stereoCalibrate with flags 0).
    Joint,
}

/// Arguments of `etlcal stereo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The left camera's images, one per pair, in the order of --right.
    #[arg(required = true, value_name = "LEFT")]
    pub left: Vec<PathBuf>,
    /// The right camera's images, as many as LEFT, pair by pair (they take every value up
    /// to the next flag).
    #[arg(long, required = true, num_args = 1.., value_name = "RIGHT")]
    pub right: Vec<PathBuf>,
    /// The board.
    #[command(flatten)]
    pub board: BoardArgs,
    /// The distortion model of both cameras (required: it changes every number).
    #[arg(long, value_enum)]
    pub model: ModelArg,
    /// Hold k3 at 0 in both cameras (OpenCV's CALIB_FIX_K3; --model opencv only).
    #[arg(long)]
    pub fix_k3: bool,
    /// Hold p1 = p2 = 0 in both cameras (OpenCV's CALIB_ZERO_TANGENT_DIST; --model opencv
    /// only).
    #[arg(long)]
    pub zero_tangent: bool,
    /// fixed: each camera's intrinsics from every image it saw the board in, held while
    /// R, T are fitted (the default, as cv2.stereoCalibrate's own default
    /// CALIB_FIX_INTRINSIC: the views seen by one camera only still count, and an error in
    /// the pair's corners cannot trade distortion against the baseline); joint: both
    /// cameras' intrinsics refined with R, T over the pairs seen by both (the least-squares
    /// optimum of the pairs; needs at least 3 pairs).
    #[arg(long, value_enum, default_value = "fixed")]
    pub intrinsics: IntrinsicsArg,
    /// Also write the pair as OpenCV FileStorage YAML (--model opencv): image_width,
    /// image_height, K1, D1, K2, D2, R, T, and Bouguet's rectification R1, R2, P1, P2, Q
    /// as cv2.stereoRectify gives them with its defaults (CALIB_ZERO_DISPARITY, alpha -1);
    /// written atomically, its directory created if missing.
    #[arg(long, value_name = "FILE.yml")]
    pub opencv_yaml: Option<PathBuf>,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

impl Args {
    /// The Zhang request of both cameras.
    fn request(&self) -> ZhangRequest {
        let model = match self.model {
            ModelArg::Paper => DistortionModel::Paper,
            ModelArg::Opencv => DistortionModel::OpenCv,
        };
        ZhangRequest { model, fix_k3: self.fix_k3, zero_tangent: self.zero_tangent }
    }

    fn mode(&self) -> StereoMode {
        match self.intrinsics {
            IntrinsicsArg::Fixed => StereoMode::FixedIntrinsics,
            IntrinsicsArg::Joint => StereoMode::Joint,
        }
    }
}

/// The board in one camera's images, each image where it is not found named on stderr.
/// Errors: those of detection, the board found in none of them (naming the camera).
fn detect(images: &[PathBuf], board: &Board, side: &str, progress: bool) -> Result<PlanarViews> {
    let found = detect_views(images, board, &crate::progress::Bar::new(progress)).map_err(|e| match e {
        Error::BoardNotFound(m) => Error::BoardNotFound(format!("{m} of the {side} camera")),
        e => e,
    })?;
    for m in &found.skipped {
        eprintln!("etlcal: warning: skipped ({side}): {m}");
    }
    Ok(found)
}

/// The pairs: each camera's view of pair k where it found the board.
fn pairs(n: usize, left: &PlanarViews, right: &PlanarViews) -> Vec<StereoPair> {
    let mut pairs = vec![StereoPair::default(); n];
    for (v, &k) in left.views.iter().zip(&left.image_index) {
        pairs[k].left = Some(v.clone());
    }
    for (v, &k) in right.views.iter().zip(&right.image_index) {
        pairs[k].right = Some(v.clone());
    }
    pairs
}

/// One camera's `etlcal zhang --json` object: its views' pairs are its images' indices.
fn camera_json(
    z: &etl_calib::zhang::ZhangResult,
    (found, view_pairs): (&PlanarViews, &[usize]),
    images: &[PathBuf],
    board: &Board,
) -> Value {
    let ids: Vec<Vec<u32>> = view_pairs
        .iter()
        .map(|k| {
            found.image_index.iter().position(|i| i == k).and_then(|p| found.ids.get(p).cloned()).unwrap_or_default()
        })
        .collect();
    result_json(z, found.image_size, images, (view_pairs, &ids), board)
}

/// The `--json` object of a result.
fn stereo_json(r: &StereoResult, args: &Args, found: [&PlanarViews; 2], board: &Board) -> Value {
    let std = r.std();
    json!({
        "left": camera_json(&r.left, (found[0], &r.left_pairs), &args.left, board),
        "right": camera_json(&r.right, (found[1], &r.right_pairs), &args.right, board),
        "rotation_rodrigues": r.rotation_rodrigues, "translation_mm": r.translation_mm,
        "rms_px": r.rms_px, "views_used": r.views_used(),
        "rotation_matrix": r.rotation_matrix(), "baseline_mm": r.baseline_mm(),
        "std": {"rotation_rodrigues": &std[..3], "translation_mm": &std[3..]},
        "per_view_rms_px": r.per_view_rms_px, "pairs_used": r.pairs_used,
        "model": match args.model { ModelArg::Paper => "paper", ModelArg::Opencv => "opencv" },
        "intrinsics": match args.intrinsics { IntrinsicsArg::Fixed => "fixed", IntrinsicsArg::Joint => "joint" },
    })
}

/// The pair as OpenCV's stereo YAML (`--opencv-yaml`): the cameras, R, T and Bouguet's
/// rectification (etl-formats' writer). Errors: the paper's model, a zero baseline,
/// images of different sizes.
fn opencv_yaml(r: &StereoResult, size: [[u32; 2]; 2]) -> Result<String> {
    if size[0] != size[1] {
        return Err(Error::invalid(
            "--opencv-yaml",
            "OpenCV's stereo rectification needs both cameras' images of one size",
        ));
    }
    let rectification = rectify((&r.left, &r.right), size[0], (r.rotation_rodrigues, r.translation_mm), true)?;
    let camera = |z: &etl_calib::zhang::ZhangResult| OpenCvCamera {
        camera_matrix: z.camera_matrix(),
        dist_coeffs: z.dist_coeffs().unwrap_or_default(),
    };
    let pair = OpenCvStereo {
        image_size: size[0],
        cameras: [camera(&r.left), camera(&r.right)],
        rotation: r.rotation_matrix(),
        translation_mm: r.translation_mm,
        rectification,
        rms_px: Some(r.rms_px),
    };
    Ok(opencv_stereo_yaml("", &pair))
}

/// Runs `etlcal stereo`.
pub fn run(args: Args) -> Result<()> {
    if args.left.len() != args.right.len() {
        return Err(Error::invalid(
            "--right",
            format!(
                "{} LEFT images but {} --right images: give one right image per left image, pair by pair",
                args.left.len(),
                args.right.len()
            ),
        ));
    }
    let request = args.request();
    // Refused before any image is read.
    request.validate(&FlagSpelling::default())?;
    let inputs = args.left.iter().chain(&args.right).map(|p| Some(p.as_path()));
    let outputs: Vec<Output<'_>> = args.opencv_yaml.iter().map(|p| Output::File(p)).collect();
    crate::output::check(inputs.chain([args.board.board.as_deref()]), &outputs)?;
    if args.opencv_yaml.is_some() && request.model != DistortionModel::OpenCv {
        return Err(Error::invalid("--opencv-yaml", "--opencv-yaml needs --model opencv (OpenCV's camera model)"));
    }
    let board = args.board.board()?;
    let left = detect(&args.left, &board, "left", !args.json)?;
    let right = detect(&args.right, &board, "right", !args.json)?;
    let flags = OpenCvFlags { fix_k3: request.fix_k3, zero_tangent: request.zero_tangent };
    let options = StereoOptions { zhang: ZhangOptions { model: request.model, flags }, mode: args.mode() };
    let pairs = pairs(args.left.len(), &left, &right);
    let sizes = [left.image_size, right.image_size];
    let r = stereo_calibrate(&pairs, sizes, &options)?;
    let mut j = stereo_json(&r, &args, [&left, &right], &board);
    if let Some(path) = &args.opencv_yaml {
        let text = opencv_yaml(&r, sizes)?;
        crate::output::create_parent(path)?;
        write_atomic(path, text.as_bytes())?;
        j["opencv_yaml"] = json!(path.display().to_string());
    }
    if args.json {
        print_json(&j);
        return Ok(());
    }
    let (om, t, s) = (r.rotation_rodrigues, r.translation_mm, r.std());
    outln!("R (Rodrigues, rad) {:.6} +- {:.6}, {:.6} +- {:.6}, {:.6} +- {:.6}", om[0], s[0], om[1], s[1], om[2], s[2]);
    outln!("T (mm) {:.4} +- {:.4}, {:.4} +- {:.4}, {:.4} +- {:.4}", t[0], s[3], t[1], s[4], t[2], s[5]);
    outln!("baseline {:.4} mm; rms {:.4} px over {} pairs", r.baseline_mm(), r.rms_px, r.views_used());
    for (name, z) in [("left", &r.left), ("right", &r.right)] {
        outln!(
            "{name}: fx {:.3}, fy {:.3}, u0 {:.3}, v0 {:.3} px, distortion {:?}; rms {:.4} px over {} views",
            z.fx,
            z.fy,
            z.u0,
            z.v0,
            z.distortion_coefficients(),
            z.rms_px,
            z.views_used
        );
    }
    Ok(())
}
