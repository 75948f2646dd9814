//! `etlcal zhang IMAGE... (--pattern CxR --square MM | --board FILE) [--model paper|opencv]
//! [--fix-k3] [--zero-tangent] [--report DIR] [--json]`: monofocal calibration of one fixed-focus camera
//! (Zhang 2000) from a whole checkerboard or a ChArUco board (each view the corners it
//! shows, no hints).
//!
//! `--model paper` (the default): the paper's distortion k1, p1, p2 in centred pixels;
//! `--json` prints `{"fx", "fy", "u0", "v0", "k1", "p1", "p2", "rms_px", "views_used",
//! "outliers"?}`. `--model opencv`: OpenCV's model (k1, k2, p1, p2, k3 in normalised
//! coordinates, the same least-squares problem as `cv2.calibrateCamera`; `--fix-k3`,
//! `--zero-tangent` as its `CALIB_FIX_K3`, `CALIB_ZERO_TANGENT_DIST`); `--json` prints
//! `{"model", "fx", "fy", "u0", "v0", "camera_matrix" (3 x 3), "dist_coeffs" ([k1, k2, p1,
//! p2, k3]), "rms_px", "views_used", "images_used", "per_view_rms_px", "std" (one standard
//! deviation of fx, fy, u0, v0, k1, k2, p1, p2, k3, as `calibrateCameraExtended`; 0 for a
//! held one), "fix_k3", "zero_tangent", "outliers"?}`.
//!
//! The flags only parse into an [`etl_calib::request::ZhangRequest`] (its default, its
//! refusal, its run), as Python's `etlcal.zhang(model=..., fix_k3=..., zero_tangent=...)`
//! does: the same names, the same result.
//!
//! Images whose board is not found are named on stderr and skipped; at least 3 views must
//! remain. `outliers` (absent when there are none, as in a calibration file) lists the
//! corners Zhang's method left out as gross outliers: `view` (the index of the IMAGE
//! argument), `image`, `point` (the corner's index in the detection's order), `corner`
//! ([i, j] on the board's corner grid), `id` (the corner's id: a ChArUco board's, a
//! checkerboard's row-major `j * cols + i`) and `residual_px` (its distance from the
//! model's projection, px).
//!
//! Both models' `--json` hold `"projection_std_px"`: the projection uncertainty in mrcal's
//! sense (`ZhangResult::projection_std`: where a calibration re-solved from new corner
//! noise projects the point seen at a pixel, the point held in the boards' frames) on a 5 x 5
//! grid spanning the image, centre and corners included (`u = i (w - 1) / 4`, `v = j (h - 1) / 4`,
//! row-major from the top left): `{"grid": [5, 5], "pixels": [[u, v], ...], "at_infinity":
//! [[std_u, std_v], ...], "views_distance_mm", "at_views_distance": [...]}`, px, at infinity
//! (a direction) and at the mean distance of the views' boards; `null` where a pixel does
//! not unproject.
//!
//! `--report DIR` also writes `index.html` (the numbers with their standard deviations) and
//! the projection uncertainty in its worst direction over a 32 x 24 grid of cells as two PNG
//! heat maps, `uncertainty_infinity.png` and `uncertainty_views_distance.png`, on one
//! logarithmic scale stated on the page (`etl_report::zhang`); the directory is replaced as
//! a set, and `--json` lists the files under `"report"`.

use std::path::PathBuf;

use serde_json::{json, Value};

use super::print_json;
use crate::board::BoardArgs;
use crate::calibrate::FlagSpelling;
use etl_calib::pipeline::detect_views;
use etl_calib::request::ZhangRequest;
use etl_calib::zhang::ZhangResult;
use etl_core::model::DistortionModel;
use etl_formats::board::Board;
use etl_formats::calibration::Outlier;
use etl_formats::output::Output;
use etl_formats::{Error, Result};

/// The distortion model of `--model`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelArg {
    /// The paper's: k1, p1, p2 in centred pixel coordinates (Eq. 17).
    Paper,
    /// OpenCV's: k1, k2, p1, p2, k3 in normalised coordinates (cv2.calibrateCamera's).
    Opencv,
}

/// Arguments of `etlcal zhang`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Images of the board (at least 3 in distinct orientations).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// The board.
    #[command(flatten)]
    pub board: BoardArgs,
    /// The distortion model.
    #[arg(long, value_enum, default_value = "paper")]
    pub model: ModelArg,
    /// Hold k3 at 0 (OpenCV's CALIB_FIX_K3; --model opencv only).
    #[arg(long)]
    pub fix_k3: bool,
    /// Hold p1 = p2 = 0 (OpenCV's CALIB_ZERO_TANGENT_DIST; --model opencv only).
    #[arg(long)]
    pub zero_tangent: bool,
    /// Also write a report into DIR (created if missing, replaced as a set): index.html
    /// with the numbers and their standard deviations, and the projection uncertainty over
    /// the image as two heat maps (at infinity and at the views' distance).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

impl Args {
    /// The request the flags ask for.
    pub fn request(&self) -> ZhangRequest {
        let model = match self.model {
            ModelArg::Paper => DistortionModel::Paper,
            ModelArg::Opencv => DistortionModel::OpenCv,
        };
        ZhangRequest { model, fix_k3: self.fix_k3, zero_tangent: self.zero_tangent }
    }
}

/// The `--json` object of an opencv-family result.
fn opencv_json(z: &ZhangResult, images: &[&PathBuf]) -> Value {
    let names = ["fx", "fy", "u0", "v0", "k1", "k2", "p1", "p2", "k3"];
    let std: serde_json::Map<String, Value> =
        names.iter().zip(&z.std).map(|(n, s)| (n.to_string(), json!(s))).collect();
    json!({"model": "opencv", "fx": z.fx, "fy": z.fy, "u0": z.u0, "v0": z.v0,
        "camera_matrix": z.camera_matrix(), "dist_coeffs": z.dist_coeffs(),
        "rms_px": z.rms_px, "views_used": z.views_used,
        "images_used": images.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "per_view_rms_px": z.per_view_rms_px, "std": std,
        "fix_k3": z.options.flags.fix_k3, "zero_tangent": z.options.flags.zero_tangent})
}

/// The `--json` object of a Zhang result `z` on images of `size` (every key but
/// `"report"`, module docs): `(image_index, ids)` give, for each of the result's views,
/// the index of its image among `images` and its corners' ids (an outlier's image and
/// corner), `board` the corner grid. `etlcal stereo` prints each camera with it.
pub fn result_json(
    z: &ZhangResult,
    size: [u32; 2],
    images: &[PathBuf],
    (image_index, ids): (&[usize], &[Vec<u32>]),
    board: &Board,
) -> Value {
    let [c0, c1, c2, ..] = z.coefficients;
    let mut j = match z.options.model {
        DistortionModel::Paper => json!({"fx": z.fx, "fy": z.fy, "u0": z.u0, "v0": z.v0, "k1": c0, "p1": c1,
            "p2": c2, "rms_px": z.rms_px, "views_used": z.views_used}),
        DistortionModel::OpenCv => {
            let used: Vec<&PathBuf> = image_index.iter().filter_map(|&k| images.get(k)).collect();
            opencv_json(z, &used)
        }
    };
    j["projection_std_px"] = projection_grid(z, size).json();
    let outliers = outliers_json(&z.outliers, (image_index, ids), images, board);
    if !outliers.is_empty() {
        j["outliers"] = Value::Array(outliers);
    }
    j
}

/// Runs `etlcal zhang`.
pub fn run(args: Args) -> Result<()> {
    let request = args.request();
    // Refused before any image is read.
    request.validate(&FlagSpelling::default())?;
    let outputs: Vec<Output<'_>> = args.report.iter().map(|d| Output::Dir(d)).collect();
    crate::output::check(args.images.iter().map(|p| Some(p.as_path())), &outputs)?;
    let board = args.board.board()?;
    let found = detect_views(&args.images, &board, &crate::progress::Bar::new(!args.json))?;
    for m in &found.skipped {
        eprintln!("etlcal: warning: skipped: {m}");
    }
    let (views, size) = (&found.views, found.image_size);
    if views.len() < 3 {
        return Err(Error::BoardNotFound(format!(
            "the board was found in {} of {} images; Zhang's method needs at least 3",
            views.len(),
            args.images.len()
        )));
    }
    let z = request.run(views, size, &FlagSpelling::default())?;
    let [c0, c1, c2, c3, c4] = z.coefficients;
    let mut j = result_json(&z, size, &args.images, (&found.image_index, &found.ids), &board);
    let grid = projection_grid(&z, size);
    if let Some(dir) = &args.report {
        let files = crate::output::write_dir_set(dir, &etl_report::zhang::ZHANG_REPORT_FILES, |staging| {
            let files = etl_report::zhang::write_zhang_report(&z, size, staging)?;
            Ok(crate::output::moved(files, staging, dir))
        })?;
        j["report"] = json!(files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>());
        if !args.json {
            outln!("wrote the report to {} (open index.html)", dir.display());
        }
    }
    if args.json {
        print_json(&j);
        return Ok(());
    }
    outln!(
        "fx {:.3} +- {:.3}, fy {:.3} +- {:.3}, u0 {:.3} +- {:.3}, v0 {:.3} +- {:.3} px",
        z.fx,
        z.std[0],
        z.fy,
        z.std[1],
        z.u0,
        z.std[2],
        z.v0,
        z.std[3]
    );
    let (rms, n) = (z.rms_px, z.views_used);
    match request.model {
        DistortionModel::Paper => outln!("k1 {c0:.4e}, p1 {c1:.4e}, p2 {c2:.4e}; rms {rms:.4} px over {n} views"),
        DistortionModel::OpenCv => {
            outln!("dist_coeffs (k1, k2, p1, p2, k3) {c0:.6}, {c1:.6}, {c2:.6}, {c3:.6}, {c4:.6}; rms {rms:.4} px over {n} views")
        }
    }
    grid.print();
    let outliers = j["outliers"].as_array().cloned().unwrap_or_default();
    if !outliers.is_empty() {
        outln!("left out {} outlier corners:", outliers.len());
    }
    for o in &outliers {
        outln!("  {} corner {} ({:.2} px)", o["image"].as_str().unwrap_or("?"), o["corner"], o["residual_px"]);
    }
    Ok(())
}

/// The columns and rows of the `--json` projection-uncertainty grid.
const GRID: [usize; 2] = [5, 5];

/// The projection uncertainty of `z` on [`GRID`] over an image of `size`.
struct ProjectionGrid {
    pixels: Vec<[f64; 2]>,
    at_infinity: Vec<Option<[f64; 2]>>,
    views_distance_mm: f64,
    at_views_distance: Vec<Option<[f64; 2]>>,
}

fn projection_grid(z: &ZhangResult, size: [u32; 2]) -> ProjectionGrid {
    let [w, h] = [size[0].max(1) as f64 - 1.0, size[1].max(1) as f64 - 1.0];
    let pixels: Vec<[f64; 2]> = (0..GRID[1])
        .flat_map(|j| {
            (0..GRID[0]).map(move |i| [i as f64 * w / (GRID[0] - 1) as f64, j as f64 * h / (GRID[1] - 1) as f64])
        })
        .collect();
    let views_distance_mm = z.views_distance_mm();
    let at = |d: Option<f64>| pixels.iter().map(|&q| z.projection_std(q, d).ok().map(|u| u.std_px)).collect();
    ProjectionGrid { at_infinity: at(None), at_views_distance: at(Some(views_distance_mm)), pixels, views_distance_mm }
}

impl ProjectionGrid {
    fn json(&self) -> Value {
        json!({"grid": GRID, "pixels": self.pixels, "at_infinity": self.at_infinity,
            "views_distance_mm": self.views_distance_mm, "at_views_distance": self.at_views_distance})
    }

    /// One line: the uncertainty at the centre and the worst on the grid.
    fn print(&self) {
        let norm = |s: &Option<[f64; 2]>| s.map(|s| s[0].hypot(s[1]));
        let worst = self.at_infinity.iter().filter_map(norm).fold(0.0, f64::max);
        let centre = norm(&self.at_infinity[GRID[0] * (GRID[1] / 2) + GRID[0] / 2]).unwrap_or(f64::NAN);
        outln!(
            "projection uncertainty at infinity (mrcal's sense): {centre:.3} px at the centre, {worst:.3} px at worst on a {} x {} grid",
            GRID[0],
            GRID[1]
        );
    }
}

/// Zhang's outliers (indices into the result's views, whose images and corners' ids are
/// `image_index` and `ids`) as the JSON of the verb: each with the index and path of its
/// image among `images`, its point index, its id and its corner [i, j] on `board`'s corner
/// grid.
fn outliers_json(
    outliers: &[Outlier],
    (image_index, ids): (&[usize], &[Vec<u32>]),
    images: &[PathBuf],
    board: &Board,
) -> Vec<Value> {
    let cols = board.corner_grid()[0].max(1);
    outliers
        .iter()
        .map(|o| {
            let image = image_index.get(o.view).copied().unwrap_or(o.view);
            let id = ids.get(o.view).and_then(|v| v.get(o.point)).copied();
            let corner = id.map(|id| [id as usize % cols, id as usize / cols]);
            json!({"view": image, "image": images.get(image).map(|p| p.display().to_string()),
                "point": o.point, "corner": corner, "id": id, "residual_px": o.residual_px})
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use etl_calib::pipeline::PlanarViews;
    use etl_calib::zhang::{zhang_with, PlanarView, ZhangOptions};
    use etl_sim::simulate::{paper_rig, NoiseModel};

    /// Zhang's outliers are named by the image they are in (its index among the IMAGE
    /// arguments, skipped images counted) and by the corner's index and [i, j].
    #[test]
    fn outliers_name_their_image_point_and_corner() {
        let sim = paper_rig(&NoiseModel::PAPER, 5);
        let mut views: Vec<PlanarView> = sim.observations.offstate_views[..5]
            .iter()
            .map(|v| PlanarView {
                board_mm: v.points.iter().map(|p| [p.world_mm[0], p.world_mm[1]]).collect(),
                pixels: v.points.iter().map(|p| p.pixel).collect(),
            })
            .collect();
        let square_mm = views[0].board_mm[1][0] - views[0].board_mm[0][0];
        let cols = views[0].board_mm.iter().filter(|b| b[1] == 0.0).count();
        let ([inner_cols, inner_rows], _) = etl_sim::simulate::LENS_OFF_BOARD;
        let board = Board::checkerboard([inner_cols, inner_rows], square_mm).unwrap();
        // The detector's ids: row-major over the board's inner corners.
        let ids = views
            .iter()
            .map(|v| {
                v.board_mm
                    .iter()
                    .map(|b| b.map(|x| (x / square_mm).round() as u32))
                    .map(|[i, j]| j * inner_cols as u32 + i)
                    .collect()
            })
            .collect();
        // Two corners moved far off, in the views of the 2nd and 5th images found.
        for (v, p) in [(1usize, 7usize), (4, cols + 2)] {
            let px = &mut views[v].pixels[p];
            *px = [px[0] + 120.0, px[1] - 60.0];
        }
        let z = zhang_with(&views, sim.observations.image_size, &ZhangOptions::default()).unwrap();
        assert_eq!(z.outliers.iter().map(|o| (o.view, o.point)).collect::<Vec<_>>(), [(1, 7), (4, cols + 2)]);
        // Six images given; the board was not found in the second one.
        let images: Vec<PathBuf> = (0..6).map(|k| PathBuf::from(format!("img{k}.png"))).collect();
        let found =
            PlanarViews { views, image_index: vec![0, 2, 3, 4, 5], ids, image_size: [1936, 1458], skipped: vec![] };
        let j = outliers_json(&z.outliers, (&found.image_index, &found.ids), &images, &board);
        assert_eq!(j.len(), 2);
        for (o, (view, image, point, corner)) in
            j.iter().zip([(2, "img2.png", 7, [7, 0]), (5, "img5.png", cols + 2, [2, 1])])
        {
            assert_eq!(o["view"], view, "{o}");
            assert_eq!(o["image"], image, "{o}");
            assert_eq!(o["point"], point, "{o}");
            assert_eq!(o["corner"], json!(corner), "{o}");
            assert_eq!(o["id"], json!(corner[1] * inner_cols + corner[0]), "{o}");
            assert!(o["residual_px"].as_f64().unwrap() > 100.0, "{o}");
        }
    }
}
