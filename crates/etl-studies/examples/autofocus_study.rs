//! Which sharpness measure to focus with: `etl_core::focus::autofocus` on the synthetic
//! camera, every measure, three working distances, several noise realisations and two noise
//! levels; prints a markdown table of the error of the found current against the true best
//! focus (bias, standard deviation over the realisations, largest error, evaluations).
//!
//! The scene is that of `tests/autofocus.rs`: the paper rig's camera looking straight at the
//! paper's board, the lens of `Optics::smooth_focus` (aperture 2.5 mm, diffraction blur
//! 0.5 px), so the best focus is exactly the current whose plane in focus is the board's.
//!
//! `cargo run --release -p etl-studies --example autofocus_study -- [REALISATIONS]` (default 8;
//! about 4 minutes on 2 cores).
use etl_core::focus::{autofocus, AutofocusOptions};
use etl_core::model::CameraModel;
use etl_image::sharpness::{sharpness, Metric};
use etl_sim::render::{render, Board, Checkerboard, Optics, Photometry, RenderOptions, Scene};

/// Working distances (camera depth of the board), mm.
const DEPTHS_MM: [f64; 3] = [95.0, 70.0, 55.0];

fn main() {
    let realisations: u64 = std::env::args().nth(1).map(|a| a.parse().expect("a count")).unwrap_or(8);
    let truth = CameraModel::paper_rig();
    let board = Board::Checkerboard(Checkerboard { inner_corners: [14, 12], square_mm: 1.5 });
    println!("| read noise (grey levels) | measure | depth (mm) | best focus (mA) | bias (mA) | std (mA) | max abs (mA) | renders |");
    println!("|---|---|---|---|---|---|---|---|");
    for read_noise in [2.0, 8.0] {
        for metric in Metric::ALL {
            for z_mm in DEPTHS_MM {
                let want = Optics::smooth_focus_current_ma(&truth, z_mm);
                let mut cam = truth;
                cam.rotation_rodrigues = [0.0; 3];
                cam.translation_mm = [-0.5 * 1.5 * 13.0, -0.5 * 1.5 * 11.0, z_mm];
                let mut errors = vec![];
                let mut renders = 0;
                for realisation in 0..realisations {
                    let mut n = 0u64;
                    let measure = |e: f64| {
                        n += 1;
                        let scene = Scene::new(cam, e, board, 0.0, CameraModel::PAPER_IMAGE_SIZE);
                        let opts = RenderOptions {
                            optics: Optics::smooth_focus(&truth, e, 2.5, 0.5),
                            photometry: Photometry { read_noise, ..Photometry::default() },
                            seed: 1000 * realisation + n,
                            ..RenderOptions::default()
                        };
                        let img = render(&scene, &opts).expect("render").image.to_dynamic().to_luma8();
                        Ok(sharpness(&img, metric).expect("sharpness"))
                    };
                    let r = autofocus(measure, &AutofocusOptions::default()).expect("autofocus");
                    errors.push(r.best_ma - want);
                    renders = renders.max(r.evaluations);
                }
                let n = errors.len() as f64;
                let mean = errors.iter().sum::<f64>() / n;
                let std = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
                let max = errors.iter().fold(0.0f64, |m, e| m.max(e.abs()));
                println!(
                    "| {read_noise} | {} | {z_mm} | {want:.2} | {mean:+.3} | {std:.3} | {max:.3} | {renders} |",
                    metric.name()
                );
            }
        }
    }
}
