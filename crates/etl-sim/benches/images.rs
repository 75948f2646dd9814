//! Rendering a 1936 x 1458 board (checkerboard, ChArUco) with defocus (target: < 100 ms) and the sharpness
//! measures on it (CPBD: < 20 ms; the reference package takes seconds).
use criterion::{criterion_group, criterion_main, Criterion};
use etl_core::model::CameraModel;
use etl_image::sharpness::{sharpness, Metric};
use etl_sim::render::{render, Optics, RenderOptions, Scene};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let truth = CameraModel::paper_rig();
    // The board 1 mm off the plane in focus: a blur of about 1.5 px.
    let scene = Scene::paper_view(&truth, 150.0, 23.0);
    let opts = RenderOptions { optics: Optics::paper_focus(&truth, 150.0, 2.5), ..RenderOptions::default() };
    c.bench_function("render_1936x1458_defocus", |b| b.iter(|| render(black_box(&scene), &opts).unwrap()));
    // The same view with the rig's ChArUco board where the checkerboard is (the markers'
    // cells add edges, and slabs to every square).
    let charuco = Scene {
        model: etl_sim::rig::charuco_frame(&truth, 1.5),
        board: etl_sim::rig::PAPER_CHARUCO.board().unwrap(),
        ..scene.clone()
    };
    c.bench_function("render_1936x1458_charuco_defocus", |b| b.iter(|| render(black_box(&charuco), &opts).unwrap()));
    let img = render(&scene, &opts).unwrap().image.to_dynamic().to_luma8();
    for (name, m) in [("cpbd", Metric::Cpbd), ("tenengrad", Metric::Tenengrad), ("laplacian", Metric::Laplacian)] {
        c.bench_function(&format!("sharpness_{name}_1936x1458"), |b| b.iter(|| sharpness(black_box(&img), m).unwrap()));
    }
    // CPBD's slowest case: without noise, blocks along the board's edges need many rows
    // of Canny classes before their edge-block test is decided.
    let clean = RenderOptions { photometry: opts.photometry.noise_free(), ..opts };
    let img = render(&scene, &clean).unwrap().image.to_dynamic().to_luma8();
    c.bench_function("sharpness_cpbd_1936x1458_noise_free", |b| {
        b.iter(|| sharpness(black_box(&img), Metric::Cpbd).unwrap())
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
