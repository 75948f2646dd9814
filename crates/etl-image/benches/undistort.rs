//! Whole-image undistortion of the paper rig's 1936 x 1458 image at 150 mA (rayon over
//! bands of rows, all the machine's threads): the maps alone, the maps at a new current
//! (`FocusMaps::maps_at`, buffers reused: the per-frame cost of a focus change), remap of
//! an 8-bit image through stored maps, and maps + remap fused (`undistort_image`).
//! `cargo bench -p etl-image --features bench --bench undistort -- --measurement-time 3`; OpenCV's side is
//! benches/undistort_opencv.py (docs/BENCHMARKS.md, "Undistortion").

use criterion::{criterion_group, criterion_main, Criterion};
use etl_core::model::CameraModel;
use etl_image::undistort::{
    remap, undistort_image, undistort_maps, FocusMaps, OutputCamera, OutputChoice, SourceImage, UndistortMaps,
};

const W: usize = 1936;
const H: usize = 1458;

fn bench(c: &mut Criterion) {
    let cam = CameraModel::paper_rig();
    let e = 150.0;
    let (k, d) = (cam.intrinsics(e).expect("K"), cam.distortion(e).expect("distortion"));
    let out = OutputCamera::of_intrinsics(&k, W, H).expect("camera");
    // A textured 8-bit image (the values do not change the work).
    let image: Vec<u8> = (0..W * H).map(|i| ((i % W) * 7 + (i / W) * 13) as u8).collect();
    let src = SourceImage::new(&image, W, H, 1).expect("image");
    let maps = undistort_maps(&k, &d, &out).expect("maps");
    // Release builds vectorise (tests run unoptimised): check here that the dispatched
    // loops (AVX2/AVX-512 where the CPU has them) give the baseline build's numbers.
    let (mut mx, mut my) = (vec![0.0f32; W * H], vec![0.0f32; W * H]);
    etl_core::undistort::undistort_maps(&k, &d, &out, 0..H, &mut mx, &mut my).expect("core maps");
    assert!(maps.map_x() == mx.as_slice() && maps.map_y() == my.as_slice(), "dispatched maps differ");
    let mut dst = vec![0u8; W * H];
    etl_core::undistort::remap(&src, &mx, &my, 0, &mut dst).expect("core remap");
    assert!(remap(&src, &maps, 0u8).expect("remap") == dst, "dispatched remap differs");
    let mut g = c.benchmark_group("undistort_1936x1458");
    g.sample_size(20);
    g.bench_function("undistort_maps", |b| b.iter(|| undistort_maps(&k, &d, &out).expect("maps")));
    let fm = FocusMaps::new(&cam, [80.0, 225.0], OutputChoice::ModelCamera { width_px: W, height_px: H }).expect("fm");
    let mut reused = UndistortMaps::default();
    let mut i = 0u32;
    g.bench_function("focus_maps_at_new_current", |b| {
        b.iter(|| {
            // A new current every frame, across the calibrated range.
            i = i.wrapping_add(1);
            fm.maps_at(80.0 + f64::from(i % 146), &mut reused).expect("maps_at");
        })
    });
    g.bench_function("remap_u8", |b| b.iter(|| remap(&src, &maps, 0u8).expect("remap")));
    g.bench_function("maps_then_remap_u8", |b| {
        b.iter(|| remap(&src, &undistort_maps(&k, &d, &out).expect("maps"), 0u8).expect("remap"))
    });
    g.bench_function("undistort_image_u8_fused", |b| {
        b.iter(|| undistort_image(&k, &d, &out, &src, 0u8).expect("undistort"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
