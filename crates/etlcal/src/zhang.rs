//! `etlcal zhang IMAGE... (--pattern CxR --square MM | --board FILE) [--json]`: monofocal
//! calibration of one fixed-focus camera (Zhang 2000, with the paper's distortion k1, p1,
//! p2 in centred pixels) from a whole checkerboard or a ChArUco board (each view the
//! corners it shows, no hints), printing `{"fx", "fy", "u0", "v0", "k1", "p1", "p2",
//! "rms_px", "views_used", "outliers"}` with `--json`. Images whose board is not found are
//! named on stderr and skipped; at least 3 views must remain. `outliers` (absent when there
//! are none, as in a calibration file) lists the corners Zhang's method left out as gross
//! outliers: `view` (the index of the IMAGE argument), `image`, `point` (the corner's index
//! in the detection's order), `corner` ([i, j] on the board's corner grid), `id` (the
//! corner's id: a ChArUco board's, a checkerboard's row-major `j * cols + i`) and
//! `residual_px` (its distance from the model's projection, px).

use std::path::PathBuf;

use serde_json::{json, Value};

use super::print_json;
use crate::board::BoardArgs;
use etl_calib::pipeline::{detect_views, PlanarViews};
use etl_calib::zhang::zhang;
use etl_formats::board::Board;
use etl_formats::calibration::Outlier;
use etl_formats::{Error, Result};

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
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Runs `etlcal zhang`.
pub fn run(args: Args) -> Result<()> {
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
    let z = zhang(views, size)?;
    let mut j = json!({"fx": z.fx, "fy": z.fy, "u0": z.u0, "v0": z.v0, "k1": z.k1, "p1": z.p1, "p2": z.p2,
        "rms_px": z.rms_px, "views_used": z.views_used});
    let outliers = outliers_json(&z.outliers, &found, &args.images, &board);
    if !outliers.is_empty() {
        j["outliers"] = serde_json::Value::Array(outliers.clone());
    }
    if args.json {
        print_json(&j);
    } else {
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
        outln!("k1 {:.4e}, p1 {:.4e}, p2 {:.4e}; rms {:.4} px over {} views", z.k1, z.p1, z.p2, z.rms_px, z.views_used);
        if !outliers.is_empty() {
            outln!("left out {} outlier corners:", outliers.len());
        }
        for o in &outliers {
            outln!("  {} corner {} ({:.2} px)", o["image"].as_str().unwrap_or("?"), o["corner"], o["residual_px"]);
        }
    }
    Ok(())
}

/// Zhang's outliers (indices into `found.views`) as the JSON of the verb: each with the
/// index and path of its image among `images`, its point index, its id and its corner
/// [i, j] on `board`'s corner grid.
fn outliers_json(outliers: &[Outlier], found: &PlanarViews, images: &[PathBuf], board: &Board) -> Vec<Value> {
    let cols = board.corner_grid()[0].max(1);
    outliers
        .iter()
        .map(|o| {
            let image = found.image_index.get(o.view).copied().unwrap_or(o.view);
            let id = found.ids.get(o.view).and_then(|v| v.get(o.point)).copied();
            let corner = id.map(|id| [id as usize % cols, id as usize / cols]);
            json!({"view": image, "image": images.get(image).map(|p| p.display().to_string()),
                "point": o.point, "corner": corner, "id": id, "residual_px": o.residual_px})
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use etl_calib::zhang::PlanarView;
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
        let z = zhang(&views, sim.observations.image_size).unwrap();
        assert_eq!(z.outliers.iter().map(|o| (o.view, o.point)).collect::<Vec<_>>(), [(1, 7), (4, cols + 2)]);
        // Six images given; the board was not found in the second one.
        let images: Vec<PathBuf> = (0..6).map(|k| PathBuf::from(format!("img{k}.png"))).collect();
        let found =
            PlanarViews { views, image_index: vec![0, 2, 3, 4, 5], ids, image_size: [1936, 1458], skipped: vec![] };
        let j = outliers_json(&z.outliers, &found, &images, &board);
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
