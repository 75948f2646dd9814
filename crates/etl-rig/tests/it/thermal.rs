//! The temperature capture on the simulated rig (the sim camera on a 240 x 180 window): a
//! camera that disconnects, a stage that stops answering and a lens that reports an error
//! each end it with one line naming the device, the table whole, and the same call goes
//! on to the fitted surface.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use etl_core::progress::NoProgress;
use etl_formats::plan::Plan;
use etl_formats::thermal::read_thermal_table;
use etl_rig::camera::sim::SimCamera;
use etl_rig::capture::{capture_thermal, CaptureOptions, ThermalReport};
use etl_rig::lens::RigLens;
use etl_rig::rig::{paper_virtual_lens, Rig};
use etl_rig::sim::SimWorld;
use etl_rig::spec::LensSpec;
use etl_rig::stage::sim::SimStage;
use etl_rig::ErrorKind;

fn plan() -> Plan {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/plan-thermal.json");
    Plan::load(&path).unwrap()
}

/// The sim rig on the window of the fixture plan's test, with the faults asked for.
fn rig_with(camera_fault: Option<u64>, stage_fault: Option<usize>) -> Rig {
    let lens = RigLens::open(&LensSpec::Virtual, paper_virtual_lens()).unwrap();
    let world = SimWorld::paper().unwrap();
    let mut camera = SimCamera::new(world.clone(), lens.virtual_device().unwrap().clone(), 3);
    camera.set_roi([1018, 449, 240, 180]).unwrap();
    if let Some(n) = camera_fault {
        camera.disconnect_after(n);
    }
    let mut stage = SimStage::new(world.clone());
    if let Some(n) = stage_fault {
        stage.stop_answering_after(n);
    }
    Rig { camera: Box::new(camera), lens, stage: Box::new(stage), sim: Some(world) }
}

fn capture(rig: &mut Rig, out: &Path) -> etl_rig::Result<ThermalReport> {
    capture_thermal(&plan(), rig, out, &CaptureOptions::default(), &NoProgress, &AtomicBool::new(false))
}

fn rows(out: &Path) -> usize {
    read_thermal_table(&out.join("thermal.csv")).map_or(0, |r| r.len())
}

#[test]
fn each_device_failure_in_a_thermal_capture_names_the_device_and_the_capture_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T");
    // The stage stops answering at the second sample's move.
    let e = capture(&mut rig_with(None, Some(1)), &out).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Timeout);
    assert!(e.to_string().starts_with("stage sim: no reply"), "{e}");
    assert_eq!(rows(&out), 1);
    // The camera disconnects in the middle of a refocus.
    let e = capture(&mut rig_with(Some(30), None), &out).unwrap_err();
    assert_eq!((e.kind(), e.to_string().starts_with("camera sim: disconnected")), (ErrorKind::LinkLost, true), "{e}");
    let after_camera = rows(&out);
    assert!((1..4).contains(&after_camera), "{after_camera} rows");
    // The lens answers a command with an error frame.
    let mut rig = rig_with(None, None);
    rig.lens.virtual_lens().unwrap().with_faults(|f| f.error_frame_next = Some(3));
    let e = capture(&mut rig, &out).unwrap_err();
    assert!(e.to_string().starts_with("lens virtual: ") && !e.to_string().contains('\n'), "{e}");
    assert_eq!(rows(&out), after_camera);
    assert!(!out.join("thermal.json").exists());
    // The same call goes on from the table to the end and fits.
    let r = capture(&mut rig_with(None, None), &out).unwrap();
    assert_eq!((r.samples_kept, r.samples_kept + r.samples_taken, r.stopped), (after_camera, 16, false));
    assert!(r.rms_ma.is_some_and(|rms| rms < 0.5), "{r:?}");
    assert!(out.join("thermal.json").exists());
}

#[test]
fn a_table_of_another_plan_is_refused_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("T");
    std::fs::create_dir(&out).unwrap();
    let table = "temperature_c,e_in_ma,e_t_ma\n40,90,0\n";
    std::fs::write(out.join("thermal.csv"), table).unwrap();
    let e = capture(&mut rig_with(None, None), &out).unwrap_err().to_string();
    assert!(
        e.contains("row 1 is at 40 degC, the plan's temperatures_c[0] 27 degC") && e.contains("choose another --out"),
        "{e}"
    );
    assert_eq!(std::fs::read_to_string(out.join("thermal.csv")).unwrap(), table);
}
