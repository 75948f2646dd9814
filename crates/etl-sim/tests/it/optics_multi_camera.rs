//! The ray-traced N-camera rig (`etl_sim::optics::multi_camera`): camera 0 is the traced
//! rig of its optics file (the same pixels), every camera focuses on the board's centre
//! within the focus table's documented tolerance, the record is the traced centroids
//! with seeded noise, and a bad design is refused naming its field.

use std::path::PathBuf;

use etl_formats::optics::OpticsFile;
use etl_sim::optics::multi_camera::focus::FOCUS_TOLERANCE_MM;
use etl_sim::optics::multi_camera::{trace_multi_camera, TracedMultiCamera, TracedRigDesign};
use etl_sim::optics::OpticalRig;

/// The Cooke fixture with 2 rings of fan rays (19 rays a spot instead of 61: a debug
/// test's budget; nothing here depends on the fan's density).
fn cooke() -> OpticalRig {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics/cooke-16mm-centred.json");
    let mut file = OpticsFile::load(&path).unwrap();
    file.procedure.fan_rings = 2;
    OpticalRig::new(file).unwrap()
}

/// Two Cooke cameras, 3 stage views.
fn small_rig() -> TracedMultiCamera {
    let design = TracedRigDesign { views: 3, ..TracedRigDesign::new() };
    trace_multi_camera(&[cooke(), cooke()], &design).unwrap()
}

#[test]
fn camera_0_is_its_optics_files_rig_and_the_record_is_its_traced_centroids() {
    let rig = small_rig();
    let (cam, own) = (&rig.cameras[0], cooke());
    assert_eq!(cam.pose, own.stage_pose());
    let view = &rig.dataset.views[1];
    let shot = view.cameras.iter().find(|s| s.camera == 0).unwrap();
    let e = shot.e_com_ma.unwrap();
    let p = shot.points.as_ref().unwrap()[5];
    let w = [p[2], p[3], view.z_w_mm];
    let at = own.at(e).unwrap();
    // The same world point through the rig's camera 0 and through the optics file's own
    // rig: the same pixel, bit for bit, which the record holds.
    let px = at.pixel(own.world_to_camera(w)).unwrap();
    assert_eq!(rig.cameras[0].world_to_camera(w), own.world_to_camera(w));
    assert_eq!([p[0], p[1]], px);
    // Camera 1 verges on the board's centre at the middle of camera 0's travel in focus.
    let [lo, hi] = rig.stage_travel_mm;
    let [a, b] = rig.cameras[0].travel_mm(&rig.board);
    assert!(hi - lo >= 4.0 && lo >= a && hi <= b, "{lo} {hi} {a} {b}");
    let c1 = rig.cameras[1].world_to_camera([13.0 * 1.5 / 2.0, 11.0 * 1.5 / 2.0, 0.5 * (a + b)]);
    assert!(c1[0].abs() < 1e-9 && c1[1].abs() < 1e-9 && c1[2] > 60.0, "{c1:?}");
    // The baseline between the rim planes' centres.
    let o = [0, 1].map(|k| rig.cameras[k].camera_to_world([0.0; 3]));
    let b = (0..3).map(|i| (o[1][i] - o[0][i]).powi(2)).sum::<f64>().sqrt();
    assert!((b - 30.0).abs() < 1e-9, "{b}");
    // Every view has both cameras, with the lens-off views of each.
    assert!(rig.dataset.views.iter().all(|v| v.cameras.len() == 2));
    assert_eq!(rig.dataset.offstate_views.len(), 10);
    assert!(rig.dataset.offstate_views.iter().all(|v| v.cameras.len() == 2));
    // The noise: seeded, about the traced pixels.
    let (a, b) = (rig.with_pixel_noise(0.05, 3), rig.with_pixel_noise(0.05, 3));
    assert_eq!(a, b);
    let q = a.views[1].cameras.iter().find(|s| s.camera == 0).unwrap().points.as_ref().unwrap()[5];
    assert!((q[0] - p[0]).abs() < 0.3 && q[0] != p[0] && q[2..] == p[2..], "{q:?} {p:?}");
}

#[test]
fn each_camera_focuses_on_the_boards_centre_within_the_tolerance() {
    let rig = small_rig();
    let [lo, hi] = rig.stage_travel_mm;
    for cam in &rig.cameras {
        for z in [lo, 0.5 * (lo + hi), hi] {
            let e = cam.focus_current_ma(&rig.board, z).unwrap();
            let traced = cam.optics.focus_distance_mm(e).unwrap();
            let want = cam.board_centre_depth_mm(&rig.board, z);
            assert!((traced - want).abs() < FOCUS_TOLERANCE_MM, "z {z}: {traced} {want}");
        }
        // Half-way between grid currents, where linear interpolation errs most.
        let t = &cam.focus;
        for i in [0, t.e_ma.len() / 2, t.e_ma.len() - 2] {
            let e = 0.5 * (t.e_ma[i] + t.e_ma[i + 1]);
            let d = cam.optics.focus_distance_mm(e).unwrap();
            let back = t.current_ma(d).unwrap();
            let traced = cam.optics.focus_distance_mm(back).unwrap();
            assert!((traced - d).abs() < FOCUS_TOLERANCE_MM, "E {e}: {traced} {d} (E {back})");
            assert!((t.distance_at_mm(e).unwrap() - d).abs() < FOCUS_TOLERANCE_MM);
        }
        assert_eq!(t.current_ma(t.range_mm()[1] + 0.1), None);
    }
    // The recorded currents are the focus currents of the recorded positions.
    for v in &rig.dataset.views {
        let e = rig.focus_currents_ma(v.z_w_mm).unwrap();
        for s in &v.cameras {
            assert_eq!(s.e_com_ma, Some(e[s.camera]));
        }
    }
}

#[test]
fn bad_designs_are_refused_naming_the_field() {
    let refused = |optics: &[OpticalRig], design: TracedRigDesign, field: &str| {
        let e = trace_multi_camera(optics, &design).unwrap_err();
        let line = e.to_string();
        assert_eq!(e.input_what(), Some(field), "{line}");
        assert!(line.contains(field) && !line.contains('\n'), "{field}: {line}");
    };
    let d = TracedRigDesign::new();
    refused(&[cooke()], d, "cameras");
    refused(&[cooke(), cooke()], TracedRigDesign { views: 2, ..d }, "views");
    refused(&[cooke(), cooke()], TracedRigDesign { baseline_mm: 1.0, ..d }, "baseline_mm");
    refused(&[cooke(), cooke()], TracedRigDesign { baseline_mm: f64::NAN, ..d }, "baseline_mm");
    refused(&[cooke(), cooke()], TracedRigDesign { focus_step_ma: 0.0, ..d }, "focus_step_ma");
    let mut other = cooke();
    other.file.procedure.lens_off_board.square_mm = 3.0;
    refused(&[cooke(), other], d, "optics[1].procedure.lens_off_board");
    // 150 mm off, camera 1 stands farther than its lens can focus: no shared travel.
    refused(&[cooke(), cooke()], TracedRigDesign { baseline_mm: 150.0, focus_step_ma: 5.0, ..d }, "baseline_mm");
}

/// Free views: the board turned about its centre (10 and 25 degrees), each camera focused
/// on the centre as on the stage board there; each corner's record is the traced pixel of
/// its world point through the free pose, and the noise reaches them after the others.
#[test]
fn free_views_are_the_tilted_boards_traced_pixels() {
    use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
    use etl_sim::optics::multi_camera::free_pose;
    let design = TracedRigDesign { views: 3, free_views: 2, ..TracedRigDesign::new() };
    let rig = trace_multi_camera(&[cooke(), cooke()], &design).unwrap();
    assert_eq!(rig.dataset.free_views.len(), 2);
    for (f, v) in rig.dataset.free_views.iter().enumerate() {
        assert_eq!(v.cameras.len(), 2, "free view {f}: both cameras");
        let (pose, z) = free_pose(&rig.board, rig.stage_travel_mm, f, 2);
        let tilt = (pose.0[0].powi(2) + pose.0[1].powi(2)).sqrt().to_degrees();
        assert!((tilt - [10.0, 25.0][f]).abs() < 1e-9, "{tilt}");
        for s in &v.cameras {
            let cam = &rig.cameras[s.camera];
            let e = s.e_com_ma.unwrap();
            assert_eq!(Some(e), cam.focus_current_ma(&rig.board, z));
            let p = s.points.as_ref().unwrap()[3];
            let w = mat_vec(&rodrigues_to_matrix(pose.0), [p[2], p[3], 0.0]);
            let w = [w[0] + pose.1[0], w[1] + pose.1[1], w[2] + pose.1[2]];
            let px = cam.pixel(&cam.optics.at(e).unwrap(), w, rig.corner).unwrap();
            assert_eq!([p[0], p[1]], px);
        }
    }
    let noisy = rig.with_pixel_noise(0.05, 3);
    let (a, b) = (&rig.dataset.free_views[0].cameras[0].points, &noisy.free_views[0].cameras[0].points);
    let d = a.as_ref().unwrap()[0][0] - b.as_ref().unwrap()[0][0];
    assert!(d != 0.0 && d.abs() < 0.5, "{d}");
    // The stage views' noise is unchanged by the free views (drawn after them).
    let plain =
        trace_multi_camera(&[cooke(), cooke()], &TracedRigDesign { views: 3, ..TracedRigDesign::new() }).unwrap();
    assert_eq!(plain.with_pixel_noise(0.05, 3).views, noisy.views);
    let bad = TracedRigDesign { free_views: 101, ..TracedRigDesign::new() };
    let e = trace_multi_camera(&[cooke(), cooke()], &bad).unwrap_err().to_string();
    assert!(e.contains("free_views: 101 is outside 0..=100"), "{e}");
}
