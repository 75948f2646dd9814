//! The demo's figures with the ChArUco rig (the default: whole boards, no per-view hints)
//! against the checkerboard rig of before (each view cut to the largest block of squares
//! that fits the frame, recorded with its first corner), over several seeds: corners used,
//! and each estimator's fx(E) error, principal point error and 2 mm PnP move error at
//! 225 mA. Prints a markdown table (docs/RESULTS.md, "ChArUco rig").
//!
//! `cargo run --release -p etl-studies --example charuco_demo -- [SEEDS]` (default 4; about
//! 25 s per seed and board on 2 cores).
use etl_core::progress::NoProgress;
use etl_sim::simulate::images::RigBoard;
use etl_studies::demo::{run_demo, DemoOptions, Validation};

fn pnp_225(v: &Validation) -> f64 {
    v.pnp_displacement_err_um.last().and_then(|p| p["err_um"].as_f64()).unwrap_or(f64::NAN)
}

fn main() {
    let seeds: u64 = std::env::args().nth(1).map(|a| a.parse().expect("a count of seeds")).unwrap_or(4);
    println!("| seed | board | views | corners | paper fx(E) | paper pp | paper 2 mm @ 225 mA | eiv fx(E) | eiv pp | eiv 2 mm @ 225 mA |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for seed in 1..=seeds {
        for (name, board) in [("ChArUco", RigBoard::Charuco), ("checkerboard blocks", RigBoard::CheckerboardBlocks)] {
            let dir = tempfile::tempdir().expect("a temporary directory");
            let options = DemoOptions { seed, stage_noise_um: 10.0, images: true, board };
            let d = run_demo(&options, dir.path(), &NoProgress).expect("the demo runs");
            let corners: usize = d.observations.views.iter().map(|v| v.points.len()).sum();
            let (p, e) = (&d.paper_validation, &d.eiv_validation);
            println!(
                "| {seed} | {name} | {} | {corners} | {:.2} % | {:.1} px | {:.1} um | {:.3} % | {:.2} px | {:.2} um |",
                d.views_detected,
                100.0 * p.fx_curve_max_rel_err,
                p.principal_point_err_px,
                pnp_225(p),
                100.0 * e.fx_curve_max_rel_err,
                e.principal_point_err_px,
                pnp_225(e),
            );
        }
    }
}
