//! Checkerboard detection + refinement on a rendered 1936 x 1458 view of the 14x12 board
//! (blur sigma 0.5, 1.5 and 3 px, read noise 2 grey levels), one image per iteration, one
//! thread per image as in `detect_many` (the refinement of the corners uses rayon).
//! `cargo bench -p etl-image --features bench --bench detect`.

use criterion::{criterion_group, criterion_main, Criterion};
use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
use etl_core::model::CameraModel;
use etl_image::checkerboard::{detect_corners, Pattern};
use etl_sim::render::{render, BitDepth, Board, Checkerboard, Optics, Photometry, RenderOptions, Scene};

fn view(blur: f64) -> image::GrayImage {
    let rot = [0.35, -0.25, 0.1];
    let e_com_ma = 150.0;
    let mut model = CameraModel::paper_rig();
    let (fx, _) = model.focal_lengths(e_com_ma);
    let board = Board::Checkerboard(Checkerboard { inner_corners: [14, 12], square_mm: 1.5 });
    let z_mm = fx * board.square_mm() / 66.0;
    let rc = mat_vec(&rodrigues_to_matrix(rot), [6.5 * 1.5, 5.5 * 1.5, 0.0]);
    model.rotation_rodrigues = rot;
    model.translation_mm = [-rc[0], -rc[1], z_mm - rc[2]];
    let scene = Scene::new(model, e_com_ma, board, 0.0, [1936, 1458]);
    let opts = RenderOptions {
        optics: Optics::uniform_blur(blur),
        photometry: Photometry { read_noise: 2.0, ..Photometry::default() },
        bit_depth: BitDepth::Eight,
        seed: 1,
    };
    render(&scene, &opts).expect("render").image.to_dynamic().to_luma8()
}

fn bench(c: &mut Criterion) {
    let pattern: Pattern = "14x12".parse().expect("pattern");
    let mut g = c.benchmark_group("detect_1936x1458_14x12");
    g.sample_size(20);
    for blur in [0.5, 1.5, 3.0] {
        let img = view(blur);
        // The same image for benches/py_overhead.py (the Python binding's overhead).
        let target =
            std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| "../../target".into(), std::path::PathBuf::from);
        let _ = std::fs::create_dir_all(target.join("criterion"));
        let _ = img.save(target.join("criterion").join(format!("detect_view_blur_{blur}.png")));
        g.bench_function(format!("blur_{blur}"), |b| b.iter(|| detect_corners(&img, pattern).expect("found")));
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
