//! `etlcal camera list` and `etlcal camera grab --camera SPEC --out FILE.png [--frames N]
//! [--exposure-us US] [--gain-db DB]`: the cameras this build can open, and one image
//! (the mean of N frames) from one of them, written atomically as PNG (8 or 16 bits as the
//! camera gives).
//!
//! With `--json`: `list` prints `{"cameras": [...]}`; `grab` prints `{"out", "image_size",
//! "frames", "timestamps_ns"}`.

use std::path::PathBuf;

use etl_formats::{write_atomic, Error, Result};
use etl_rig::camera::average;
use etl_rig::rig::{list_cameras, open_camera};
use etl_rig::spec::CameraSpec;
use serde_json::json;

use super::print_json;

/// Arguments of `etlcal camera`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to do.
    #[command(subcommand)]
    pub command: CameraCommand,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The camera subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum CameraCommand {
    /// The cameras this build can open (sim; aravis's with the aravis feature).
    List,
    /// Grab an image (the mean of --frames frames) into a PNG file.
    Grab(GrabArgs),
}

/// Arguments of `etlcal camera grab`.
#[derive(clap::Args, Debug)]
pub struct GrabArgs {
    /// The camera: sim, files:DIR, aravis:NAME, v4l2:/dev/videoN.
    #[arg(long, value_name = "SPEC")]
    pub camera: String,
    /// The PNG to write.
    #[arg(long, value_name = "FILE.png")]
    pub out: PathBuf,
    /// Frames averaged (1..=1000).
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
    /// Exposure time to set first, us (the camera's own when absent).
    #[arg(long, value_name = "US")]
    pub exposure_us: Option<f64>,
    /// Gain to set first, dB (the camera's own when absent).
    #[arg(long, value_name = "DB")]
    pub gain_db: Option<f64>,
    /// Seed of the sim camera's noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Runs `etlcal camera`.
pub fn run(args: Args) -> Result<()> {
    match args.command {
        CameraCommand::List => {
            let cameras = list_cameras()?;
            if args.json {
                print_json(&json!({ "cameras": cameras }));
            } else {
                cameras.iter().for_each(|c| outln!("{c}"));
            }
            Ok(())
        }
        CameraCommand::Grab(g) => grab(g, args.json),
    }
}

fn grab(g: GrabArgs, json_out: bool) -> Result<()> {
    if !(1..=1000).contains(&g.frames) {
        return Err(Error::invalid_value("--frames", g.frames, format!("--frames {} must lie in 1..=1000", g.frames)));
    }
    let ext = g.out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if ext.as_deref() != Some("png") {
        return Err(Error::invalid("--out", format!("--out {}: camera grab writes PNG (FILE.png)", g.out.display())));
    }
    let mut camera = open_camera(&g.camera.parse::<CameraSpec>()?, g.seed)?;
    if let Some(us) = g.exposure_us {
        camera.set_exposure_us(us)?;
    }
    if let Some(db) = g.gain_db {
        camera.set_gain_db(db)?;
    }
    let frames = (0..g.frames).map(|_| camera.grab()).collect::<etl_rig::Result<Vec<_>>>()?;
    let pixels = average(&frames, &camera.name())?;
    write_atomic(&g.out, &pixels.to_png()?)?;
    let timestamps: Vec<u64> = frames.iter().map(|f| f.timestamp_ns).collect();
    if json_out {
        print_json(
            &json!({"out": g.out, "image_size": pixels.size(), "frames": g.frames, "timestamps_ns": timestamps}),
        );
    } else {
        let [w, h] = pixels.size();
        outln!("wrote {} ({w} x {h} px, mean of {} frames)", g.out.display(), g.frames);
    }
    Ok(())
}
