//! The simulated rig as images, detected by the pipeline: every detected corner's world
//! point is where the true camera sees the detected pixel (ids and board coordinates
//! right), for the ChArUco rig (whole boards, no hints, partial views) and for the
//! checkerboard rig with per-view sub-boards and `first_corner` hints (the datasets written
//! before ChArUco).
use etl_calib::pipeline::dataset::{default_detector, observations_from_dataset};
use etl_core::model::CameraModel;
use etl_core::progress::NoProgress;
use etl_formats::board::Board;
use etl_formats::observations::Observations;
use etl_sim::simulate::images::{dataset_truth, render_rig, ImageOptions, RigBoard};
use etl_sim::simulate::{paper_rig, NoiseModel, Simulation};

/// RMS and largest distance (px) between each detected pixel and the true camera's
/// projection of its world point at the view's true stage position and current.
fn pixel_errors(sim: &Simulation, truth: &CameraModel, obs: &Observations) -> (f64, f64, usize) {
    let (mut s2, mut worst, mut n) = (0.0, 0.0f64, 0);
    for (k, v) in obs.views.iter().enumerate() {
        let (dz, de) = (sim.true_dz_mm[k], sim.true_de_ma[k]);
        let e = v.e_com_ma.unwrap() + de;
        for p in &v.points {
            let [x, y, z] = p.world_mm;
            let q = truth.project([x, y, z + dz], e).unwrap();
            let d = (q[0] - p.pixel[0]).hypot(q[1] - p.pixel[1]);
            s2 += d * d;
            worst = worst.max(d);
            n += 1;
        }
    }
    ((s2 / n as f64).sqrt(), worst, n)
}

#[test]
fn charuco_and_hinted_checkerboard_views_give_the_true_world_points() {
    let sim = paper_rig(&NoiseModel::PAPER, 5);
    let mut corners = vec![];
    for board in [RigBoard::Charuco, RigBoard::CheckerboardBlocks] {
        let dir = tempfile::tempdir().unwrap();
        let options = ImageOptions { board, ..ImageOptions::default() };
        let dataset = render_rig(&sim, dir.path(), &options, 5, &NoProgress).unwrap();
        let charuco = board == RigBoard::Charuco;
        assert_eq!(matches!(dataset.board, Board::Charuco(_)), charuco);
        assert_eq!(matches!(dataset.offstate_board(), Board::Charuco(_)), charuco);
        let hints = dataset.views.iter().filter(|v| v.first_corner.is_some() || v.board.is_some()).count();
        assert_eq!(hints, if charuco { 0 } else { 15 });
        let path = dir.path().join("dataset.json");
        dataset.save(&path).unwrap();
        let (obs, summary) = observations_from_dataset(&dataset, &path, &default_detector(), &NoProgress).unwrap();
        assert_eq!((summary.views_detected, obs.offstate_views.len()), (15, 10), "{board:?}: {summary:?}");
        let (rms, worst, n) = pixel_errors(&sim, &dataset_truth(&sim.truth, &options), &obs);
        eprintln!("{board:?}: {n} corners, rms {rms:.4} px, worst {worst:.4} px");
        assert!(rms < 0.03 && worst < 0.15, "{board:?}: rms {rms} px, worst {worst} px over {n} corners");
        corners.push(n);
    }
    // The partial ChArUco views keep the corners a checkerboard block must cut off.
    assert!(corners[0] > 2200 && corners[1] < 1700, "{corners:?}");
}
