use etl_core::model::CameraModel;

use super::*;
use etl_formats::ErrorKind;

const W: usize = 1936;
const H: usize = 1458;

/// A smooth scene on the ideal (undistorted) pixel grid, grey levels in [20, 230].
fn scene(x: f64, y: f64) -> f64 {
    125.0 + 60.0 * (x / 37.0).sin() * (y / 53.0).cos() + 45.0 * ((x + y) / 91.0).sin()
}

#[test]
fn parallel_maps_are_the_cores_single_pass() {
    let cam = CameraModel::paper_rig();
    let (k, d) = (cam.intrinsics(150.0).unwrap(), cam.distortion(150.0).unwrap());
    let out = OutputCamera::of_intrinsics(&k, W, H).unwrap();
    let maps = undistort_maps(&k, &d, &out).unwrap();
    let (mut mx, mut my) = (vec![0.0f32; W * H], vec![0.0f32; W * H]);
    etl_core::undistort::undistort_maps(&k, &d, &out, 0..H, &mut mx, &mut my).unwrap();
    assert_eq!((maps.width_px(), maps.height_px()), (W, H));
    assert!(maps.map_x() == mx.as_slice() && maps.map_y() == my.as_slice());
}

/// Ground truth: the distorted image of a known scene (each observed pixel takes the scene
/// at its undistorted position, by the model's own inversion), undistorted again, is the
/// scene on the output grid, up to bilinear interpolation of a smooth function.
#[test]
fn undistorting_a_distorted_scene_gives_the_scene_back() {
    let cam = CameraModel::paper_rig();
    let (w, h) = (640, 480);
    for e in [80.0, 225.0] {
        let (k, d) = (cam.intrinsics(e).unwrap(), cam.distortion(e).unwrap());
        let mut observed = vec![0.0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let ideal = cam.undistort([x as f64, y as f64], e).unwrap();
                observed[y * w + x] = scene(ideal[0], ideal[1]) as f32;
            }
        }
        let src = SourceImage::new(&observed, w, h, 1).unwrap();
        let out = OutputCamera::of_intrinsics(&k, w, h).unwrap();
        let maps = undistort_maps(&k, &d, &out).unwrap();
        let img = undistort_image(&k, &d, &out, &src, -1.0).unwrap();
        assert!(img == remap(&src, &maps, -1.0).unwrap(), "fused and two-step differ");
        let mut worst = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let (sx, sy) = (maps.map_x()[y * w + x], maps.map_y()[y * w + x]);
                if sx < 0.0 || sy < 0.0 || sx > (w - 1) as f32 || sy > (h - 1) as f32 {
                    // Outside the observed image: the border value.
                    assert!(img[y * w + x] == -1.0 || sx > -1.0 && sy > -1.0 && sx < w as f32 && sy < h as f32);
                    continue;
                }
                worst = worst.max((img[y * w + x] as f64 - scene(x as f64, y as f64)).abs());
            }
        }
        // Bilinear interpolation of the scene errs by at most |f''| / 8 per axis (unit
        // spacing): (60 / 37^2 + 45 / 91^2) / 8 * 2 axes = 0.024 grey levels.
        assert!(worst < 0.03, "E = {e}: worst {worst} grey levels");
    }
}

#[test]
fn three_channels_u8_and_u16_fused_equals_maps_then_remap() {
    let cam = CameraModel::paper_rig();
    let (k, d) = (cam.intrinsics(110.0).unwrap(), cam.distortion(110.0).unwrap());
    let (w, h) = (200, 150);
    let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 251) as u8).collect();
    let out = OutputCamera::new(0.9 * k.fx, 0.9 * k.fy, 100.0, 75.0, 180, 140).unwrap();
    let maps = undistort_maps(&k, &d, &out).unwrap();
    let src = SourceImage::new(&rgb, w, h, 3).unwrap();
    let a = remap(&src, &maps, 0).unwrap();
    assert_eq!(a.len(), 180 * 140 * 3);
    assert!(a == undistort_image(&k, &d, &out, &src, 0).unwrap());
    let g16: Vec<u16> = (0..w * h).map(|i| (i * 131 % 65521) as u16).collect();
    let src = SourceImage::new(&g16, w, h, 1).unwrap();
    assert!(remap(&src, &maps, 9).unwrap() == undistort_image(&k, &d, &out, &src, 9).unwrap());
}

#[test]
fn focus_maps_are_the_exact_maps_and_refuse_outside_the_range() {
    let cam = CameraModel::paper_rig();
    let fm = FocusMaps::new(&cam, [80.0, 225.0], OutputChoice::ModelCamera { width_px: 300, height_px: 200 }).unwrap();
    let mut maps = UndistortMaps::default();
    for e in [80.0, 137.3, 225.0] {
        fm.maps_at(e, &mut maps).unwrap();
        let (k, d) = (cam.intrinsics(e).unwrap(), cam.distortion(e).unwrap());
        assert_eq!(maps, undistort_maps(&k, &d, &OutputCamera::of_intrinsics(&k, 300, 200).unwrap()).unwrap());
    }
    let before = maps.clone();
    for e in [79.99, 225.01, f64::NAN] {
        let err = fm.maps_at(e, &mut maps).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Precondition);
        assert!(err.to_string().starts_with("e_com_ma (mA) of the undistortion maps = "), "{err}");
    }
    assert_eq!(maps, before, "nothing written on error");
    let bad = FocusMaps::new(&cam, [225.0, 80.0], OutputChoice::ModelCamera { width_px: 3, height_px: 2 }).unwrap_err();
    assert!(bad.to_string().contains("e_com_range_ma"), "{bad}");
    let zero =
        FocusMaps::new(&cam, [80.0, 225.0], OutputChoice::ModelCamera { width_px: 0, height_px: 2 }).unwrap_err();
    assert!(zero.to_string().contains("output width_px"), "{zero}");
}

#[test]
fn bad_sizes_are_errors_and_leave_the_maps_whole() {
    let cam = CameraModel::paper_rig();
    let (k, d) = (cam.intrinsics(150.0).unwrap(), cam.distortion(150.0).unwrap());
    let mut maps = undistort_maps(&k, &d, &OutputCamera::of_intrinsics(&k, 8, 4).unwrap()).unwrap();
    let before = maps.clone();
    let zero = OutputCamera { height_px: 0, ..OutputCamera::of_intrinsics(&k, 8, 4).unwrap() };
    let err = undistort_maps_into(&k, &d, &zero, &mut maps).unwrap_err();
    assert!(err.to_string().contains("output height_px"), "{err}");
    assert_eq!(maps, before);
}
