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

/// The fake camera's GenICam description with a lens: `FocalPower` (dpt, bounds those of
/// the paper lens over `limits_ma`) and `LensTemperature` (degC), float registers in the
/// fake camera's free memory.
fn genicam_with_a_lens(limits_ma: [f64; 2]) -> String {
    let physics = etl_core::physics::LensPhysics::paper();
    let [lo, hi] = limits_ma.map(|e| physics.power_dpt(e));
    let (xml, _) = aravis::FakeCamera::new("lens").genicam_xml();
    let register = |name: &str, address: &str| {
        format!(
            "<FloatReg Name=\"{name}Register\" NameSpace=\"Custom\"><Address>{address}</Address><Length>4</Length>\
             <AccessMode>RW</AccessMode><pPort>Device</pPort><Endianess>BigEndian</Endianess></FloatReg>"
        )
    };
    let lens = format!(
        "<Category Name=\"LensControl\" NameSpace=\"Custom\"><pFeature>FocalPower</pFeature>\
         <pFeature>LensTemperature</pFeature></Category>\
         <Float Name=\"FocalPower\" NameSpace=\"Custom\"><pValue>FocalPowerRegister</pValue><Min>{lo}</Min><Max>{hi}</Max></Float>\
         {}\
         <Float Name=\"LensTemperature\" NameSpace=\"Custom\"><pValue>LensTemperatureRegister</pValue><Min>-40</Min><Max>125</Max></Float>\
         {}</RegisterDescription>",
        register("FocalPower", "0x1000"),
        register("LensTemperature", "0x1008")
    );
    xml.replacen("<pFeature>Debug</pFeature>", "<pFeature>Debug</pFeature><pFeature>LensControl</pFeature>", 1)
        .replacen("</RegisterDescription>", &lens, 1)
}

#[test]
fn aravis_fake_gv_camera_drives_its_lens_through_focal_power() {
    use aravis::prelude::*;
    use etl_core::lens::Lens;
    use etl_rig::lens::genicam::GenicamLens;
    use etl_rig::spec::LensSpec;
    let dir = tempfile::tempdir().unwrap();
    let xml = dir.path().join("lens-camera.xml");
    std::fs::write(&xml, genicam_with_a_lens([40.0, 250.0])).unwrap();
    // A GigE Vision fake camera on the loopback interface, serving that description.
    let _server = aravis::GvFakeCamera::new_full(Some("127.0.0.1"), Some("ETL1"), Some(&xml.to_string_lossy()));
    let spec = "genicam:127.0.0.1,temperature=LensTemperature".parse::<LensSpec>().unwrap();
    let LensSpec::Genicam(g) = &spec else { panic!() };
    let camera = etl_rig::camera::aravis::open_arv_camera("127.0.0.1").unwrap();
    camera.set_float("LensTemperature", 31.5).unwrap();
    let mut lens = GenicamLens::on_camera(camera.clone(), g).unwrap();
    // The current goes out as the paper lens's power at it and comes back from the power.
    let physics = etl_core::physics::LensPhysics::paper();
    let e = lens.set_current_ma(150.0).unwrap();
    assert!((e - 150.0).abs() < 1e-3, "{e}");
    let dpt = camera.float("FocalPower").unwrap();
    assert!((dpt - physics.power_dpt(150.0)).abs() < 1e-4, "{dpt} dpt");
    assert!((lens.current_ma().unwrap() - 150.0).abs() < 1e-3);
    assert_eq!(lens.temperature_c().unwrap(), 31.5);
    // Beyond the feature's bounds: clamped, as a driver clamps to its limits.
    assert!((lens.set_current_ma(280.0).unwrap() - 250.0).abs() < 1e-3);
    let limits = lens.limits_ma().unwrap();
    assert!((limits[0] - 40.0).abs() < 1e-3 && (limits[1] - 250.0).abs() < 1e-3, "{limits:?}");
    // A feature the camera does not have is refused in one line naming it.
    let missing = "genicam:127.0.0.1,feature=OpticControllerCurrent,unit=ma".parse::<LensSpec>().unwrap();
    let LensSpec::Genicam(m) = &missing else { panic!() };
    let e = GenicamLens::on_camera(camera, m).map(|_| ()).unwrap_err().to_string();
    assert!(e.starts_with("lens genicam:127.0.0.1,feature=OpticControllerCurrent,unit=ma: the camera has no feature OpticControllerCurrent"), "{e}");
}
