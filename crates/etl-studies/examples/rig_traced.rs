//! The acceptance of a calibrated 2-camera rig on ray-traced optics (docs/RESULTS.md):
//! `cargo run --release -p etl-studies --example rig_traced -- [TRIALS] [SEED]
//! [--chief] [--in-focus] [--stop-scale S] [--sigma-px S] [--free-views N]
//! [--requests default,hold-a0,moving,moving-tilted] [OPTICS_FILE [OPTICS_FILE]]`
//! (default 200 trials from seed 1, spot centroids, every request, two Cooke cameras of
//! fixtures/optics; one file: both cameras; `--chief`: the corners as chief rays' hits; `--in-focus`: the random point
//! drawn first and each camera focused on it, instead of random settings;
//! `--stop-scale S`: every camera's stop scaled by S in (0, 1]; `--sigma-px S`: the
//! pixel noise instead of camera 0's procedure's, 0 for the bias alone; `--free-views N`:
//! N free views of the board tilted, which `moving-tilted` gives each camera's own
//! calibration as tilted views); a markdown
//! summary per request on stdout.

use std::path::PathBuf;

use etl_formats::optics::OpticsFile;
use etl_formats::{Error, Result};
use etl_sim::optics::procedure::CornerAs;
use etl_sim::optics::OpticalRig;
use etl_studies::optics::stopped_down;
use etl_studies::rig_traced::{rig_traced, trace, PointDraw, RigRequest, RigTracedDesign, TracedRigDesign};

/// What the command line asks.
struct Args {
    trials: usize,
    seed: u64,
    corner: CornerAs,
    stop_scale: f64,
    sigma_px: Option<f64>,
    requests: Vec<RigRequest>,
    free_views: usize,
    point: PointDraw,
    files: Vec<PathBuf>,
}

fn parse() -> Result<Args> {
    let bad = |what: &str, m: String| Error::invalid(what.to_owned(), m);
    let mut a = Args {
        trials: 200,
        seed: 1,
        corner: CornerAs::Centroid,
        stop_scale: 1.0,
        sigma_px: None,
        requests: RigRequest::ALL.to_vec(),
        free_views: 0,
        point: PointDraw::RandomSettings,
        files: vec![],
    };
    let mut numbers = vec![];
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--chief" => a.corner = CornerAs::Chief,
            "--in-focus" => a.point = PointDraw::InFocus,
            "--stop-scale" => {
                let v = it.next().and_then(|s| s.parse().ok());
                a.stop_scale = v.ok_or_else(|| bad("--stop-scale", "--stop-scale takes a number in (0, 1]".into()))?;
            }
            "--sigma-px" => {
                let v = it.next().and_then(|s| s.parse().ok()).filter(|s: &f64| *s >= 0.0);
                a.sigma_px = Some(v.ok_or_else(|| bad("--sigma-px", "--sigma-px takes a number >= 0".into()))?);
            }
            "--free-views" => {
                let v = it.next().and_then(|s| s.parse().ok());
                a.free_views = v.ok_or_else(|| bad("--free-views", "--free-views takes a whole number".into()))?;
            }
            "--requests" => {
                let list = it.next().unwrap_or_default();
                a.requests = list
                    .split(',')
                    .map(|r| match r {
                        "default" => Ok(RigRequest::Default),
                        "hold-a0" => Ok(RigRequest::HoldA0),
                        "moving" => Ok(RigRequest::MovingCentre),
                        "moving-tilted" => Ok(RigRequest::MovingTilted),
                        other => Err(bad(
                            "--requests",
                            format!("--requests: {other} is not default, hold-a0, moving or moving-tilted"),
                        )),
                    })
                    .collect::<Result<_>>()?;
            }
            n if numbers.len() < 2 && n.parse::<u64>().is_ok() => numbers.push(n.parse::<u64>().unwrap_or(0)),
            file => a.files.push(file.into()),
        }
    }
    a.trials = numbers.first().map_or(a.trials, |n| *n as usize);
    a.seed = numbers.get(1).copied().unwrap_or(a.seed);
    Ok(a)
}

fn main() -> Result<()> {
    let args = parse()?;
    let fixture = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics/cooke-16mm-centred.json");
    let files = match args.files.len() {
        0 => vec![fixture.clone(), fixture],
        1 => vec![args.files[0].clone(), args.files[0].clone()],
        _ => args.files.clone(),
    };
    let optics = files
        .iter()
        .map(|f| OpticalRig::new(stopped_down(OpticsFile::load(f)?, args.stop_scale)?))
        .collect::<Result<Vec<_>>>()?;
    let started = std::time::Instant::now();
    let design = TracedRigDesign { corner: args.corner, free_views: args.free_views, ..TracedRigDesign::new() };
    let rig = trace(&optics, &design)?;
    let views: Vec<usize> =
        (0..2).map(|k| rig.dataset.views.iter().filter(|v| v.cameras.iter().any(|s| s.camera == k)).count()).collect();
    println!(
        "{} + {} ({:?} corners), stage travel {:.2}..{:.2} mm, views per camera {views:?}; traced in {:.1} s\n",
        optics[0].file.name,
        optics[1].file.name,
        args.corner,
        rig.stage_travel_mm[0],
        rig.stage_travel_mm[1],
        started.elapsed().as_secs_f64()
    );
    let sigma_px = args.sigma_px.unwrap_or(optics[0].file.procedure.pixel_noise_px);
    println!("pixel noise {sigma_px} px\n");
    for request in &args.requests {
        let r = rig_traced(
            &rig,
            &RigTracedDesign { request: *request, sigma_px, point: args.point },
            args.trials,
            args.seed,
        )?;
        println!("{}\n", r.markdown());
    }
    Ok(())
}
