//! The report shows a calibration's warnings and its outliers (view or setting view,
//! point, residual), and says nothing of either when there are none.

use std::path::Path;

use etl_formats::calibration::Outlier;
use etl_formats::Calibration;

#[test]
fn the_report_lists_warnings_and_outliers() {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/service/calibration.json");
    let mut cal = Calibration::load(&fixture).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let provenance = etl_report::Provenance { inputs: vec![], priors: None, written_unix_s: None };
    etl_report::write_report(&cal, None, None, &provenance, dir.path()).unwrap();
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    assert!(!html.contains("Warnings</h2>") && !html.contains("Outliers</h2>"));
    cal.outliers = vec![Outlier { view: 2, point: 17, residual_px: 412.5 }];
    cal.setting_outliers = vec![Outlier { view: 5, point: 3, residual_px: 9.0 }];
    cal.warnings = vec!["1 of 2311 corners (0.04 %) are outliers (reprojection error > 5 robust sigmas)".into()];
    etl_report::write_report(&cal, None, None, &provenance, dir.path()).unwrap();
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    assert!(html.contains(
        "<h2 id=\"warnings\">Warnings</h2><ul><li>1 of 2311 corners (0.04 %) are outliers (reprojection error &gt; 5"
    ));
    assert!(html.contains("<p>2 corners left out of the final solve"), "{html}");
    assert!(html.contains("<tr><td>view 2</td><td>17</td><td>412.50</td></tr>"), "{html}");
    // Zhang's outliers of the per-setting baseline, named as setting views.
    assert!(html.contains("<tr><td>setting view 5</td><td>3</td><td>9.00</td></tr>"), "{html}");
}
