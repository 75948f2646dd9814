//! The capture procedures on the simulated rig: a small plan captured whole; a camera
//! that disconnects, a stage that stops answering and a lens that reports an error, each
//! ending the capture with one line naming the device, the dataset whole, and the same
//! call resuming; bad plans refused before anything is written.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use etl_core::progress::NoProgress;
use etl_formats::dataset::Dataset;
use etl_formats::plan::{Plan, FORMAT};
use etl_rig::camera::sim::SimCamera;
use etl_rig::capture::{capture_views, CaptureOptions};
use etl_rig::lens::RigLens;
use etl_rig::rig::{paper_virtual_lens, Rig, RigSpec};
use etl_rig::sim::SimWorld;
use etl_rig::spec::{CameraSpec, LensSpec, StageSpec};
use etl_rig::stage::sim::SimStage;
use etl_rig::ErrorKind;

/// Two views of the paper rig's ChArUco board at currents in focus there.
fn plan(extra: &str) -> Plan {
    let text = format!(
        r#"{{"format": "etlcal.plan/1",
            "board": {{"type": "charuco", "squares": [15, 13], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100"}},
            "stage_mm": [22.0, 16.0], "frames": 1, "focus": "current", "currents_ma": [149.7, 169.7]{extra}}}"#
    );
    etl_formats::parse_json(&text, Path::new("plan.json"), FORMAT).unwrap()
}

fn spec() -> RigSpec {
    RigSpec {
        camera: CameraSpec::Sim,
        lens: LensSpec::Virtual,
        stage: StageSpec::Sim,
        sim_seed: 3,
        sim_roi: None,
        virtual_lens: paper_virtual_lens(),
    }
}

/// The sim rig with its camera and stage built here, so that a test can set their faults.
fn rig_with(camera_fault: Option<u64>, stage_fault: Option<usize>) -> Rig {
    let lens = RigLens::open(&LensSpec::Virtual, paper_virtual_lens()).unwrap();
    let world = SimWorld::paper().unwrap();
    let mut camera = SimCamera::new(world.clone(), lens.virtual_device().unwrap().clone(), 3);
    if let Some(n) = camera_fault {
        camera.disconnect_after(n);
    }
    let mut stage = SimStage::new(world.clone());
    if let Some(n) = stage_fault {
        stage.stop_answering_after(n);
    }
    Rig { camera: Box::new(camera), lens, stage: Box::new(stage), sim: Some(world) }
}

fn capture(plan: &Plan, rig: &mut Rig, out: &Path) -> etl_rig::Result<etl_rig::capture::CaptureReport> {
    capture_views(plan, rig, out, &CaptureOptions::default(), &NoProgress, &AtomicBool::new(false))
}

fn no_temporaries(dir: &Path) {
    for sub in ["", "views", "offstate"] {
        let Ok(entries) = std::fs::read_dir(dir.join(sub)) else { continue };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            assert!(!name.starts_with('.'), "temporary left: {sub}/{name}");
        }
    }
}

#[test]
fn each_device_failure_names_the_device_keeps_the_dataset_whole_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("D");
    let plan = plan("");
    // The stage stops answering at the second view.
    let e = capture(&plan, &mut rig_with(None, Some(1)), &out).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Timeout);
    assert!(e.to_string().starts_with("stage sim: no reply"), "{e}");
    let d: Dataset = etl_formats::read_json(&out.join("dataset.json"), etl_formats::dataset::FORMAT).unwrap();
    assert_eq!(d.views.len(), 1);
    // The camera disconnects in the next view: the dataset keeps its one view.
    let e = capture(&plan, &mut rig_with(Some(1), None), &out).unwrap_err();
    assert_eq!((e.kind(), e.to_string().starts_with("camera sim: disconnected")), (ErrorKind::LinkLost, true), "{e}");
    assert_eq!(Dataset::load(&out.join("dataset.json")).unwrap().views.len(), 1);
    // The lens answers the next command with an error frame.
    let mut rig = rig_with(None, None);
    rig.lens.virtual_lens().unwrap().with_faults(|f| f.error_frame_next = Some(3));
    let e = capture(&plan, &mut rig, &out).unwrap_err();
    assert!(e.to_string().starts_with("lens virtual: "), "{e}");
    assert!(!e.to_string().contains('\n'));
    // The same call resumes: the first view is verified and kept, the second taken.
    let r = capture(&plan, &mut rig_with(None, None), &out).unwrap();
    assert_eq!((r.views_kept, r.views_taken, r.stopped), (1, 1, false));
    let d = Dataset::load(&out.join("dataset.json")).unwrap();
    assert_eq!(d.views.iter().map(|v| v.z_w_mm).collect::<Vec<_>>(), vec![22.0, 16.0]);
    for v in &d.views {
        // Approached from below and recorded as commanded (the driver's 0.07 mA steps).
        let planned = if v.z_w_mm == 22.0 { 149.7 } else { 169.7 };
        assert!((v.e_in_ma - planned).abs() < 0.05, "{v:?}");
        assert!((26.5..28.0).contains(&v.temperature_c), "{v:?}");
        let img = etl_image::read_image(&out.join(&v.image)).unwrap();
        assert_eq!([img.width(), img.height()], d.image_size);
    }
    no_temporaries(&out);
    // Done: one more run keeps everything and takes nothing.
    let r = capture(&plan, &mut rig_with(None, None), &out).unwrap();
    assert_eq!((r.views_kept, r.views_taken), (2, 0));
}

#[test]
fn bad_plans_and_positions_beyond_the_stage_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("D");
    let mut rig = Rig::open(&spec()).unwrap();
    let mut far = plan("");
    far.stage_mm[1] = 400.0;
    let e = capture(&far, &mut rig, &out).unwrap_err().to_string();
    assert!(e.contains("stage_mm[1]") && e.contains("outside the travel of stage sim"), "{e}");
    let mut none = plan("");
    none.stage_mm.clear();
    none.currents_ma = Some(vec![]);
    let e = capture(&none, &mut rig, &out).unwrap_err().to_string();
    assert!(e.contains("stage_mm: the plan has no stage positions"), "{e}");
    let mut zero = plan("");
    zero.frames = 0;
    assert!(capture(&zero, &mut rig, &out).unwrap_err().to_string().contains("frames: 0 frames"));
    let e = capture(&plan(""), &mut rig, &out).map(|_| ());
    assert!(e.is_ok());
    let _ = std::fs::remove_dir_all(&out);
    let mut auto = plan("");
    auto.focus = etl_formats::plan::Focus::Autofocus;
    auto.currents_ma = None;
    let e = capture(&auto, &mut rig, &out).unwrap_err().to_string();
    assert!(e.contains("autofocus_range_ma"), "{e}");
    assert!(!out.exists(), "a refused plan wrote {}", out.display());
}

#[test]
fn autofocus_finds_the_current_in_focus_and_lens_off_views_come_first() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("D");
    let mut auto = plan(r#", "offstate_views": 2"#);
    auto.focus = etl_formats::plan::Focus::Autofocus;
    auto.currents_ma = None;
    auto.stage_mm = vec![22.0];
    auto.offstate_board = Some(etl_sim::rig::LENS_OFF_CHARUCO.board().unwrap());
    let options = CaptureOptions { autofocus_range_ma: Some([130.0, 170.0]), ..CaptureOptions::default() };
    let mut rig = Rig::open(&spec()).unwrap();
    let r = capture_views(&auto, &mut rig, &out, &options, &NoProgress, &AtomicBool::new(false)).unwrap();
    assert_eq!((r.offstate_taken, r.views_taken), (2, 1));
    let d = Dataset::load(&out.join("dataset.json")).unwrap();
    assert_eq!(d.offstate_views.len(), 2);
    // The simulated lens's focus law puts the board at 22 mm in focus near E_com 150 mA
    // (E_in about 0.3 mA lower at 27 degC); the search's sharpness peak is within a few mA.
    let e = d.views[0].e_in_ma;
    assert!((e - 149.7).abs() < 6.0, "autofocus chose {e} mA");
}

/// A camera double: the paper rig's board at 150 mA rendered at stage positions `z_mm`,
/// one frame each, in order (a lens whose image still moves, then rests).
struct MovingBoard {
    frames: Vec<etl_rig::camera::Pixels>,
    grabbed: usize,
}

impl MovingBoard {
    fn new(z_mm: &[f64]) -> MovingBoard {
        use etl_sim::render::{render, Optics, RenderOptions, Scene};
        let truth = etl_sim::rig::charuco_frame(&etl_core::model::CameraModel::paper_rig(), 1.5);
        let board = etl_sim::rig::PAPER_CHARUCO.board().unwrap();
        let frames = z_mm
            .iter()
            .map(|&z| {
                let scene = Scene::new(truth, 150.0, board, z, etl_core::model::CameraModel::PAPER_IMAGE_SIZE);
                let options =
                    RenderOptions { optics: Optics::paper_focus(&truth, 150.0, 2.5), ..RenderOptions::default() };
                etl_rig::camera::Pixels::from_dynamic(render(&scene, &options).unwrap().image.to_dynamic())
            })
            .collect();
        MovingBoard { frames, grabbed: 0 }
    }
}

impl etl_rig::camera::Camera for MovingBoard {
    fn name(&self) -> String {
        "camera moving".into()
    }
    fn grab(&mut self) -> etl_rig::Result<etl_rig::camera::Frame> {
        let k = self.grabbed.min(self.frames.len() - 1);
        self.grabbed += 1;
        Ok(etl_rig::camera::Frame { pixels: self.frames[k].clone(), timestamp_ns: k as u64 })
    }
    fn set_exposure_us(&mut self, _: f64) -> etl_rig::Result<()> {
        Ok(())
    }
    fn set_gain_db(&mut self, _: f64) -> etl_rig::Result<()> {
        Ok(())
    }
    fn info(&mut self) -> etl_rig::Result<etl_rig::camera::CameraInfo> {
        Ok(etl_rig::camera::CameraInfo { spec: "moving".into(), model: "double".into(), image_size: [1936, 1458] })
    }
}

#[test]
fn settling_waits_until_the_corners_stop_moving_and_times_out_naming_the_lens() {
    use etl_rig::capture::settle::settle_on_corners;
    let board = etl_sim::rig::PAPER_CHARUCO.board().unwrap();
    let options = CaptureOptions::default();
    // The board's image drifts (0.2, 0.05 mm of stage: pixels of motion), then rests.
    let mut camera = MovingBoard::new(&[22.2, 22.05, 22.0, 22.0, 22.0]);
    settle_on_corners(&mut camera, &board, &options, "lens virtual", "views[0]").unwrap();
    assert_eq!(camera.grabbed, 4, "settled on the first pair of frames that agree");
    // An image that keeps moving: no settling within the time-out.
    let mut camera = MovingBoard::new(&[22.2, 22.0, 22.2, 22.0]);
    camera.frames.extend(camera.frames.clone());
    let quick = CaptureOptions { settle_timeout_s: 0.0, ..options };
    let e = settle_on_corners(&mut camera, &board, &quick, "lens virtual", "views[0]").unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Timeout);
    assert!(e.to_string().starts_with("lens virtual: did not settle within 0 s"), "{e}");
    // No board at all: the view is refused, named.
    let blank = etl_rig::camera::Pixels::Mono8(image::GrayImage::from_pixel(1936, 1458, image::Luma([128])));
    let mut camera = MovingBoard { frames: vec![blank], grabbed: 0 };
    let e = settle_on_corners(&mut camera, &board, &quick, "lens virtual", "views[3]").unwrap_err();
    assert_eq!(e.kind(), ErrorKind::ViewRefused);
    assert!(e.to_string().starts_with("views[3]: no board in any frame"), "{e}");
}

#[test]
fn a_lens_with_dynamics_is_waited_for_and_the_view_taken() {
    let dir = tempfile::tempdir().unwrap();
    let config = etl_hw::virtual_lens::VirtualLensConfig {
        dynamics: Some(etl_core::physics::dynamics::LensDynamics::PUBLISHED),
        ..paper_virtual_lens()
    };
    let mut rig = Rig::open(&RigSpec { virtual_lens: config, ..spec() }).unwrap();
    let mut one = plan("");
    one.stage_mm.truncate(1);
    one.currents_ma = Some(vec![149.7]);
    // The lens creeps in wall time: on a loaded machine frames come slowly and the corners
    // move more between them, so settling may take longer than the default time-out allows.
    let patient = CaptureOptions { settle_timeout_s: 120.0, ..CaptureOptions::default() };
    let out = dir.path().join("D");
    let r = capture_views(&one, &mut rig, &out, &patient, &NoProgress, &AtomicBool::new(false)).unwrap();
    assert_eq!(r.views_taken, 1);
}

/// The drift check both a view and a refocus make: refused above the limit, naming the
/// view and both temperatures; kept at or below it.
#[test]
fn a_temperature_drift_above_the_limit_is_refused_naming_the_view() {
    let options = CaptureOptions { max_temperature_change_c: 0.5, ..CaptureOptions::default() };
    assert!(options.check_temperature_drift(30.0, 30.5, "view 3", "the view").is_ok());
    assert!(options.check_temperature_drift(30.0, 29.6, "view 3", "the view").is_ok());
    let message = options.check_temperature_drift(30.0, 30.61, "view 3", "the refocus").unwrap_err().to_string();
    assert!(message.contains("view 3"), "{message}");
    assert!(message.contains("30.00 to 30.61 degC during the refocus, more than 0.5 degC"), "{message}");
}
