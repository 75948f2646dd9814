//! The 2 mm move on the ray-traced Cooke rig (`etl_studies::optics`), one noise seed at
//! 150 mA: the per-current OpenCV calibration measures it to microns, the fixed-centre
//! model with A0 held tens of microns off, and the default estimator, which leaves A0
//! free, far off (the fixed centre's scale along the axis is nearly unobservable from the
//! procedure's fronto-parallel ETL views: docs/RESULTS.md, "The fixed centre on a
//! ray-traced rig").

use std::path::Path;

use etl_formats::optics::OpticsFile;
use etl_sim::optics::OpticalRig;
use etl_studies::optics::{optics_pnp, CAMERAS};

#[test]
fn a_per_current_calibration_measures_the_move_and_the_fixed_centre_does_not() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics/cooke-16mm-centred.json");
    let rig = OpticalRig::new(OpticsFile::load(&path).unwrap()).unwrap();
    let study = optics_pnp(&rig, 1, &[150.0]).unwrap();
    assert!((0.5..1.0).contains(&study.pupil_shift_mm), "{}", study.pupil_shift_mm);
    let [(default, _), (held, _), _, _, _, _, _, (joint_moving, _), _, (direct, _)] = study.rows[0].bias_rms_um;
    let table = study.markdown();
    assert_eq!(table.matches(CAMERAS[9]).count(), 1, "{table}");
    assert!(direct.abs() < 10.0, "{table}");
    assert!((5.0..60.0).contains(&held.abs()), "{table}");
    assert!(default.abs() > 100.0, "{table}");
    // With the tilted setting views in the joint solve the moving centre's move is seen
    // (fitted -0.75 mm against the traced -0.67 mm) and the 2 mm move measured as the
    // per-current calibration does.
    assert!(joint_moving.abs() < 15.0, "{table}");
    let fitted = study.fitted_moves_mm[0].0;
    assert!((fitted - study.pupil_move_mm).abs() < 0.2, "fitted {fitted} traced {}", study.pupil_move_mm);
}

/// The moving centre with the tilted setting views, A0 held, over three noise seeds: each
/// joint solve finds the traced pupil's move (-0.67 mm; fitted -0.74 mm). Started only
/// from the stage views' moving-centre fit, one seed of three settled in another minimum
/// (+0.9 +- 2.8 mm over the seeds); the second start, the centre held still while the
/// tilted views fix fx(E) and then released, finds it (`pipeline::setting_views`).
#[test]
fn the_joint_moving_centre_finds_the_pupils_move_on_every_seed() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics/cooke-16mm-centred.json");
    let rig = OpticalRig::new(OpticsFile::load(&path).unwrap()).unwrap();
    let study = optics_pnp(&rig, 3, &[150.0]).unwrap();
    for (k, (mean, std)) in study.fitted_moves_mm.iter().enumerate() {
        assert!((mean - study.pupil_move_mm).abs() < 0.15, "{k}: fitted {mean} traced {}", study.pupil_move_mm);
        assert!(*std < 0.05, "{k}: the fitted move spreads {std} mm over the seeds");
    }
    let [.., (joint_moving, _), (joint_moving_held, _), _] = study.rows[0].bias_rms_um;
    assert!(joint_moving.abs() < 10.0 && joint_moving_held.abs() < 10.0, "{}", study.markdown());
}

/// The floor of any central model (`etl_studies::optics::floor`), Cooke rig at 150 mA,
/// noise-free: a per-current pinhole fits the chief rays to a few thousandths of a pixel
/// and measures the move to under 1 um with them; the spots' centroids it fits ten times
/// worse, and the move comes out microns off (docs/RESULTS.md, "The floor of any central
/// model on these rigs").
#[test]
fn a_central_model_fits_the_chief_rays_and_not_the_spots_centroids() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics/cooke-16mm-centred.json");
    let rig = OpticalRig::new(OpticsFile::load(&path).unwrap()).unwrap();
    let floor = etl_studies::optics::floor::central_floor(&rig, &[150.0]).unwrap();
    let (row, table) = (floor.rows[0], floor.markdown());
    assert!(row.chief.rms_px < 0.01 && row.chief.move_error_um.abs() < 1.0, "{table}");
    assert!(row.centroid.rms_px > 0.04 && row.centroid.move_error_um.abs() > 2.0, "{table}");
    assert!((row.centroid.fx_px / row.chief.fx_px - 1.0).abs() > 1e-3, "{table}");
}
