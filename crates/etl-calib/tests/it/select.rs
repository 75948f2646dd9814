//! `calibrate --distortion auto --focal-degree auto` (issue 16): the model chosen by
//! held-out views (etl_calib::pipeline::select) on simulated corners with the paper's
//! noise model (stage, current, pixel and A0 errors) and the default estimator
//! (errors-in-variables), 20 seeds per rig:
//! - the strong-distortion rig (k1 = -0.3, k2 = 0.15): the opencv family, every seed;
//! - the paper rig: the paper's family, every seed; with the focal degree free as well,
//!   paper + cubic in at least 19 of 20 seeds (as issue 16 asks; 19 here, 98 of the 100
//!   seeds 61..160: docs/RESULTS.md, "Model selection").
//!
//! Bad input: a candidate list that is empty (OpenCV's flags with the paper family are the
//! request's refusal: `request.rs`).

use etl_calib::pipeline::select::{select, A0Source, Candidates};
use etl_calib::pipeline::CalibrateOptions;
use etl_core::model::DistortionModel;
use etl_formats::ThermalRef;
use etl_sim::simulate::{paper_rig, strong_rig, NoiseModel, Simulation};

const SEEDS: std::ops::Range<u64> = 1..21;

fn chosen(sim: &Simulation, candidates: &Candidates) -> (DistortionModel, usize) {
    let r = select(
        &sim.observations,
        &A0Source::Offstate,
        Some(&ThermalRef::paper()),
        &CalibrateOptions::default(),
        candidates,
    )
    .unwrap();
    let table = r.calibration.model_selection.as_ref().unwrap();
    table.validate().unwrap();
    let c = table.chosen().unwrap();
    let m = r.report.model;
    // The calibration is the chosen candidate's.
    assert_eq!((m.distortion_model().name(), m.focal_degree()), (c.distortion_model.as_str(), c.focal_degree));
    assert_eq!(table.candidates.len(), candidates.families.len() * candidates.focal_degrees.len());
    (m.distortion_model(), m.focal_degree())
}

#[test]
fn auto_chooses_the_opencv_family_on_the_strong_rig() {
    let candidates = Candidates::fixed_centre(DistortionModel::ALL.to_vec(), vec![3]);
    let picks: Vec<_> = SEEDS.map(|s| chosen(&strong_rig(&NoiseModel::PAPER, s), &candidates)).collect();
    let opencv = picks.iter().filter(|p| p.0 == DistortionModel::OpenCv).count();
    eprintln!("strong rig: opencv in {opencv} of 20 seeds");
    assert!(opencv >= 19, "{picks:?}");
}

#[test]
fn auto_chooses_the_papers_family_and_mostly_the_cubic_on_the_paper_rig() {
    let candidates = Candidates::fixed_centre(DistortionModel::ALL.to_vec(), (1..=5).collect());
    let picks: Vec<_> = SEEDS.map(|s| chosen(&paper_rig(&NoiseModel::PAPER, s), &candidates)).collect();
    let paper = picks.iter().filter(|p| p.0 == DistortionModel::Paper).count();
    let cubic = picks.iter().filter(|p| **p == (DistortionModel::Paper, 3)).count();
    eprintln!("paper rig: paper family in {paper} of 20 seeds, paper + cubic in {cubic}: {picks:?}");
    assert!(paper >= 19, "{picks:?}");
    assert!(cubic >= 19, "{picks:?}");
    // Never a degree the data plainly refute (the cubic term is 7 sigma on this rig).
    assert!(picks.iter().all(|p| p.1 >= 2), "{picks:?}");
}

#[test]
fn candidates_are_needed() {
    let sim = paper_rig(&NoiseModel::PAPER, 1);
    let none = Candidates::fixed_centre(vec![], vec![3]);
    let e = select(&sim.observations, &A0Source::Given(sim.a0), None, &CalibrateOptions::default(), &none).unwrap_err();
    assert!(e.to_string().contains("at least one family"), "{e}");
}

/// The rate behind the figure above, on seeds the rule was not designed on (61..=160;
/// about 2.5 min with `--release`): `cargo test --release -p etl-calib --test it select:: --
/// --ignored --nocapture`. Recorded in docs/RESULTS.md ("Model selection").
#[test]
#[ignore = "100 auto calibrations: run with --release"]
fn auto_chooses_the_cubic_on_100_fresh_seeds_of_the_paper_rig() {
    let candidates = Candidates::fixed_centre(DistortionModel::ALL.to_vec(), (1..=5).collect());
    let picks: Vec<_> = (61..161).map(|s| (s, chosen(&paper_rig(&NoiseModel::PAPER, s), &candidates))).collect();
    let others: Vec<_> = picks.iter().filter(|p| p.1 != (DistortionModel::Paper, 3)).collect();
    eprintln!("paper rig, seeds 61..=160: paper + cubic in {} of 100; others: {others:?}", 100 - others.len());
    assert!(others.len() <= 5, "{others:?}");
}
