//! The rig-efficiency study's code path on a few trials (the 300-trial figures of
//! docs/RESULTS.md come from its example in release mode).

use etl_studies::rig_efficiency::{rig_efficiency, FX_CURRENTS_MA};

#[test]
fn rig_efficiency_runs_and_its_bounds_are_of_the_right_size() {
    let r = rig_efficiency(4, 21).unwrap();
    assert_eq!((r.trials, r.failed), (4, 0));
    assert_eq!(r.quantities.len(), 6 + 2 * FX_CURRENTS_MA.len());
    for q in &r.quantities {
        assert!(q.crlb_std > 0.0 && q.monte_carlo_std > 0.0, "{q:?}");
        // Four trials: the spread is known to a factor of a few, no better.
        assert!(q.efficiency > 0.02 && q.efficiency < 50.0, "{q:?}");
        assert!(q.bias.abs() < 6.0 * q.crlb_std, "{q:?}");
    }
    let baseline = r.quantities.iter().find(|q| q.name == "T_x (mm)").unwrap();
    assert!(baseline.crlb_std > 1e-3 && baseline.crlb_std < 1.0, "{baseline:?}");
    assert!(r.markdown().contains("| cam1 fx(150 mA) (px) |"));
}
