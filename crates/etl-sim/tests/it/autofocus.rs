//! Autofocus on the synthetic camera: the paper rig's camera looking straight at
//! the paper's board at three working distances; the current of best focus found from
//! rendered images within 0.5 mA of the truth with at most 15 renders.
//!
//! The truth is exact: the lens is [`Optics::smooth_focus`] (dioptric focus affine in the
//! current, diffraction blur 0.5 px), so the best focus of a board square to the axis is the
//! current whose plane in focus lies at the board's depth
//! ([`Optics::smooth_focus_current_ma`]). A tilted board would have no single best focus
//! (at 200 mA the paper's board spans about 16 mA of focus, and each measure weights its
//! strips differently), and the paper's piecewise-linear focus law would give the blur
//! different slopes on the two sides of focus (see `smooth_focus`).
//!
//! Which measure: all three gradient measures land within 0.3 mA here, with read noise 2
//! and 8 grey levels (`examples/autofocus_study.rs`, docs/RESULTS.md "Autofocus"); the test
//! uses Tenengrad, the default of the temperature procedure. CPBD cannot drive the coarse
//! scan (it is 0 beyond about 1 px of blur), which the second test shows.
use etl_core::focus::{autofocus, AutofocusOptions, AutofocusResult};
use etl_core::model::CameraModel;
use etl_image::sharpness::{sharpness, Metric};
use etl_sim::render::{render, Board, Checkerboard, Optics, RenderOptions, Scene};

/// Autofocus with `metric` on the board at camera depth `z_mm`; returns the result and the
/// true best focus.
fn focus_on(z_mm: f64, metric: Metric) -> (AutofocusResult, f64) {
    let truth = CameraModel::paper_rig();
    let board = Board::Checkerboard(Checkerboard { inner_corners: [14, 12], square_mm: 1.5 });
    let mut cam = truth;
    cam.rotation_rodrigues = [0.0; 3];
    cam.translation_mm = [-0.5 * 1.5 * 13.0, -0.5 * 1.5 * 11.0, z_mm];
    let mut renders = 0u64;
    let measure = |e: f64| -> etl_core::Result<f64> {
        renders += 1;
        let scene = Scene::new(cam, e, board, 0.0, CameraModel::PAPER_IMAGE_SIZE);
        let opts =
            RenderOptions { optics: Optics::smooth_focus(&truth, e, 2.5, 0.5), seed: renders, ..Default::default() };
        let img = render(&scene, &opts).expect("render").image.to_dynamic().to_luma8();
        Ok(sharpness(&img, metric).expect("sharpness"))
    };
    let r = autofocus(measure, &AutofocusOptions::default()).unwrap();
    (r, Optics::smooth_focus_current_ma(&truth, z_mm))
}

#[test]
fn autofocus_finds_the_best_current_within_half_a_milliampere() {
    for z_mm in [95.0, 70.0, 55.0] {
        let (r, want) = focus_on(z_mm, Metric::Tenengrad);
        println!(
            "board at {z_mm} mm: best focus {want:.3} mA, found {:.3} mA ({:+.3}) with {} renders",
            r.best_ma,
            r.best_ma - want,
            r.evaluations
        );
        assert!(r.evaluations <= 15);
        assert!((r.best_ma - want).abs() < 0.5, "found {} mA, truth {want} mA", r.best_ma);
    }
}

#[test]
fn cpbd_cannot_drive_the_coarse_scan() {
    // Far from focus CPBD says nothing about the board (its blurred edges have no width
    // CPBD can measure, and what remains is decided by noise edges), so the coarse scan
    // lands tens of mA from focus.
    let (r, want) = focus_on(70.0, Metric::Cpbd);
    assert!((r.best_ma - want).abs() > 10.0, "found {} mA, truth {want} mA", r.best_ma);
}
