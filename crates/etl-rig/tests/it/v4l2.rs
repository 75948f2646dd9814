//! The V4L2 backend without a device (cargo feature `v4l2`, Linux): a device that is not
//! there fails in one line naming it; its formats and conversions are the unit tests of
//! `camera::v4l2_format`.

use etl_rig::camera::v4l2::V4l2Camera;
use etl_rig::rig::open_camera;
use etl_rig::spec::CameraSpec;
use etl_rig::ErrorKind;

#[test]
fn v4l2_a_missing_device_fails_in_one_line_naming_it() {
    let path = std::path::Path::new("/dev/video-etlcal-absent");
    let e = V4l2Camera::open(path).map(|_| ()).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::LinkLost);
    let text = e.to_string();
    assert!(text.starts_with("camera v4l2:/dev/video-etlcal-absent: cannot open: "), "{text}");
    assert!(text.contains("No such file") && !text.contains('\n'), "{text}");
    let spec = "v4l2:/dev/video-etlcal-absent".parse::<CameraSpec>().unwrap();
    let e = open_camera(&spec, 0).map(|_| ()).unwrap_err().to_string();
    assert!(e.starts_with("camera v4l2:/dev/video-etlcal-absent: cannot open"), "{e}");
    // A file that is not a V4L2 device.
    let e = V4l2Camera::open(std::path::Path::new("/dev/null")).map(|_| ()).unwrap_err().to_string();
    assert!(e.starts_with("camera v4l2:/dev/null: ") && !e.contains('\n'), "{e}");
}
