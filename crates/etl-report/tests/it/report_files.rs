//! The report's index.html and its figures: every figure it lists is referenced as SVG and
//! PNG, every file it references exists and is non-empty, and every figure written is
//! shown. On the simulated paper rig (known truth), calibrated by both estimators.

use std::collections::BTreeSet;
use std::path::Path;

use etl_calib::pipeline::{calibrate, CalibrateOptions};
use etl_core::calib::Estimator;
use etl_formats::calibration::Calibration;
use etl_formats::ThermalRef;
use etl_report::{write_report, Provenance, REPORT_FIGURES};
use etl_sim::simulate::{paper_rig, NoiseModel, Simulation};

/// Every local target of src="..." and href="..." in `html` (anchors and URLs left out).
fn references(html: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for key in ["src=\"", "href=\""] {
        for part in html.split(key).skip(1) {
            let target = &part[..part.find('"').unwrap()];
            if !target.starts_with('#') && !target.contains("://") {
                out.insert(target.to_string());
            }
        }
    }
    out
}

/// Checks the report in `dir`; returns the stems of the figures index.html lists.
fn check_report(dir: &Path, written: &[std::path::PathBuf]) -> Vec<&'static str> {
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    let refs = references(&html);
    for r in &refs {
        let f = dir.join(r);
        assert!(f.is_file(), "index.html references {r}, which does not exist");
        assert!(std::fs::metadata(&f).unwrap().len() > 0, "{r} is empty");
    }
    let listed: Vec<&str> =
        REPORT_FIGURES.iter().map(|f| f.0).filter(|stem| html.contains(&format!("id=\"{stem}\""))).collect();
    for stem in &listed {
        for ext in ["svg", "png"] {
            assert!(refs.contains(&format!("{stem}.{ext}")), "{stem}.{ext} listed but not referenced");
        }
    }
    // Every figure file written is shown.
    for f in written.iter().filter(|f| f.extension().is_some_and(|e| e == "svg" || e == "png")) {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        assert!(refs.contains(&name), "{name} written but not referenced");
    }
    // No reference to anything outside the report.
    assert!(refs.iter().all(|r| !r.contains('/') && !r.contains("..")), "{refs:?}");
    listed
}

fn calibrated(sim: &Simulation, estimator: Estimator) -> Calibration {
    let th = ThermalRef::paper();
    let options = CalibrateOptions { estimator, ..Default::default() };
    calibrate(&sim.observations, &sim.a0, Some(&th), &options).unwrap().calibration
}

#[test]
fn both_estimators_show_every_figure_and_each_file_exists() {
    let sim = paper_rig(&NoiseModel::PAPER, 3);
    for estimator in [Estimator::Paper, Estimator::EIV_PAPER] {
        let cal = calibrated(&sim, estimator);
        let dir = tempfile::tempdir().unwrap();
        let provenance = Provenance {
            inputs: vec![("calibration".into(), "calibration.json".into())],
            priors: Some(Provenance::priors_of(&estimator)),
            written_unix_s: None,
        };
        let r = write_report(&cal, Some(&sim.observations), cal.thermal.as_ref(), &provenance, dir.path()).unwrap();
        let listed = check_report(dir.path(), &r.files);
        // With observations and a covariance, all of them.
        assert_eq!(listed, REPORT_FIGURES.iter().map(|f| f.0).collect::<Vec<_>>(), "{estimator:?}");
        let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
        for name in ["kf0x", "a9", "px/mA²", "etlcal version", "priors", "|r| &gt; 0.9"] {
            assert!(html.contains(name), "{estimator:?}: index.html lacks {name}");
        }
        // What the covariance accounts for, from the file's covariance_noise.
        let noise = "px, stage position 10.0 um and current 0.4 mA per view";
        assert!(
            html.contains("recorded (25 x 25); accounts for pixel noise 0.") && html.contains(noise),
            "{estimator:?}"
        );
        // The distortion triples are nearly collinear in w: strongly correlated (the
        // paper's own a-values are poorly determined), so pairs are listed.
        assert!(
            html.contains("<b>a1</b> &amp; <b>a2</b>") || html.contains("<b>a2</b> &amp; <b>a3</b>"),
            "{estimator:?}"
        );
    }
}

#[test]
fn a_calibration_without_covariance_or_observations_says_what_is_missing() {
    let sim = paper_rig(&NoiseModel::PAPER, 4);
    let mut cal = calibrated(&sim, Estimator::Paper);
    cal.covariance = None;
    let dir = tempfile::tempdir().unwrap();
    let r = write_report(&cal, None, None, &Provenance::default(), dir.path()).unwrap();
    let listed = check_report(dir.path(), &r.files);
    assert_eq!(listed, ["focal", "distortion", "distortion_field"]);
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    assert!(html.contains("has no covariance"));
    assert!(html.contains("No observations were given"));
    assert!(html.contains("not recorded in the calibration file"), "priors unknown: said so");
    // A paper file of before covariance_noise: its covariance was of the pixel noise alone.
    let mut old = calibrated(&sim, Estimator::Paper);
    old.covariance_noise = None;
    let dir = tempfile::tempdir().unwrap();
    write_report(&old, None, None, &Provenance::default(), dir.path()).unwrap();
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    assert!(html.contains("accounts for the pixel noise alone (written before covariance_noise was recorded)"));
}

#[test]
fn a_missing_output_directory_is_refused_and_nothing_is_written() {
    let sim = paper_rig(&NoiseModel::PAPER, 5);
    let cal = Calibration::from_model(&sim.truth, [1936, 1458], [80.0, 225.0]);
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("absent");
    let e = write_report(&cal, None, None, &Provenance::default(), &missing).unwrap_err().to_string();
    assert!(e.contains("does not exist"), "{e}");
    assert!(!missing.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// Issue 16: a calibration of the strong-distortion rig chosen by `--distortion auto`
/// (the opencv family): every figure, OpenCV's five coefficients with their units in the
/// tables, and the comparison table of the candidates.
#[test]
fn opencv_family_and_the_model_selection_table_are_reported() {
    use etl_calib::pipeline::select::{select, A0Source, Candidates};
    use etl_core::model::DistortionModel;
    let sim = etl_sim::simulate::strong_rig(&NoiseModel::PAPER, 5);
    let candidates = Candidates::fixed_centre(DistortionModel::ALL.to_vec(), vec![3]);
    let r = select(
        &sim.observations,
        &A0Source::Given(sim.a0),
        Some(&ThermalRef::paper()),
        &Default::default(),
        &candidates,
    )
    .unwrap();
    let cal = r.calibration;
    assert_eq!(cal.distortion_model.as_deref(), Some("opencv"));
    let dir = tempfile::tempdir().unwrap();
    let written =
        write_report(&cal, Some(&sim.observations), cal.thermal.as_ref(), &Provenance::default(), dir.path()).unwrap();
    let listed = check_report(dir.path(), &written.files);
    assert_eq!(listed, REPORT_FIGURES.iter().map(|f| f.0).collect::<Vec<_>>());
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    for needle in [
        "model: opencv distortion, focal degree 3 (31 numbers)",
        "a15",
        "k2 = a4 w² + a5 w + a6",
        "<td><b>k3</b></td><td>none</td>",
        "id=\"model-selection\"",
        "leave-one-view-out",
        "<tr class=\"chosen\"><td>opencv</td><td>3</td><td>31</td>",
        "k1, k2, p1, p2, k3 (each a quadratic in 1/f",
    ] {
        assert!(html.contains(needle), "index.html lacks {needle}");
    }
    // The paper candidate's row, with its (much larger) prediction error.
    assert!(html.contains("<tr><td>paper</td><td>3</td><td>25</td>"), "paper row");
}
