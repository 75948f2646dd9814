//! The aravis backend on aravis's in-process fake camera, through the real library: the
//! GenICam features (exposure), the stream path (queued buffers), frame size and
//! timestamps. Runs with the cargo feature `aravis` (libaravis-dev installed).

use etl_rig::camera::aravis::AravisCamera;
use etl_rig::camera::{Camera, Pixels};
use etl_rig::rig::open_camera;
use etl_rig::spec::CameraSpec;

#[test]
fn the_fake_camera_sets_exposure_and_streams_frames_of_its_size_with_rising_timestamps() {
    let mut camera = AravisCamera::open("Fake_1").unwrap();
    camera.set_exposure_us(5000.0).unwrap();
    assert!((camera.exposure_us().unwrap() - 5000.0).abs() < 1.0);
    let info = camera.info().unwrap();
    assert!(info.image_size[0] > 0 && info.image_size[1] > 0, "{info:?}");
    let frames: Vec<_> = (0..4).map(|_| camera.grab().unwrap()).collect();
    for f in &frames {
        assert_eq!(f.pixels.size(), info.image_size);
        assert!(matches!(f.pixels, Pixels::Mono8(_) | Pixels::Mono16(_)));
        assert!(f.timestamp_ns > 0);
    }
    for pair in frames.windows(2) {
        assert!(pair[1].timestamp_ns > pair[0].timestamp_ns, "{} then {}", pair[0].timestamp_ns, pair[1].timestamp_ns);
    }
    // The fake camera's pattern is not blank: the pixels carry data from the stream.
    let Pixels::Mono8(g) = &frames[3].pixels else { panic!("the fake camera streams Mono8") };
    let (lo, hi) = g.pixels().fold((255u8, 0u8), |(lo, hi), p| (lo.min(p.0[0]), hi.max(p.0[0])));
    assert!(hi > lo, "a uniform frame");
}

#[test]
fn a_spec_opens_the_fake_camera_and_an_unknown_one_fails_naming_it() {
    let mut camera = open_camera(&"aravis:Fake_2".parse::<CameraSpec>().unwrap(), 0).unwrap();
    assert!(camera.info().unwrap().model.to_lowercase().contains("fake"));
    let e = open_camera(&CameraSpec::Aravis("NoSuchCamera-42".into()), 0).map(|_| ()).unwrap_err().to_string();
    assert!(e.starts_with("camera aravis:NoSuchCamera-42: "), "{e}");
}
