//! `etlcal diff A.json B.json (--e-in MA --t C | --e-com MA) [--grid CxR] [--heatmap
//! FILE.png] [--allow-extrapolation] [--json]`: how far apart two calibrations put the same
//! direction at one lens setting, over the whole image (etl_calib::diff: the
//! intrinsics-only difference and the one left after the best rotation, RMS and maximum,
//! px). `--heatmap` writes the best-rotation differences as a PNG (dark blue 0, yellow the
//! maximum; grey where a pixel does not map through both).
//!
//! `--json` keys: `a`, `b`, the setting's (`e_in_ma`, `temperature_c`, `e_com_ma`,
//! `extrapolated`: B's camera's, which is A's when both have the same thermal part),
//! `grid`, `rms_px`, `max_px`, `rotated_rms_px`, `rotated_max_px`, `rotation_rodrigues`,
//! `unmapped`, `heatmap` (the path, or null).

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use crate::setting::SettingFlags;
use etl_calib::diff::{projection_diff, DEFAULT_GRID};
use etl_formats::output::Output;
use etl_formats::{Error, Result};

/// Arguments of `etlcal diff`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The first calibration (etlcal.calibration/1): its pixels' directions.
    #[arg(value_name = "A.json")]
    pub a: PathBuf,
    /// The second calibration: where it projects them.
    #[arg(value_name = "B.json")]
    pub b: PathBuf,
    /// The setting of both (E_com through each calibration's thermal part).
    #[command(flatten)]
    pub setting: SettingFlags,
    /// The grid of pixels compared, columns x rows (each 1..=1000).
    #[arg(long, value_name = "CxR", default_value = "64x48", value_parser = parse_grid)]
    pub grid: [usize; 2],
    /// Write the best-rotation differences as a PNG heat map (atomically).
    #[arg(long, value_name = "FILE.png")]
    pub heatmap: Option<PathBuf>,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

fn parse_grid(s: &str) -> std::result::Result<[usize; 2], String> {
    let bad = || format!("{s:?} is not a grid CxR (e.g. {}x{})", DEFAULT_GRID[0], DEFAULT_GRID[1]);
    let (c, r) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    Ok([c.parse().map_err(|_| bad())?, r.parse().map_err(|_| bad())?])
}

/// Runs `etlcal diff`.
pub fn run(args: Args) -> Result<()> {
    let outputs: Vec<Output<'_>> = args.heatmap.iter().map(|p| Output::File(p)).collect();
    crate::output::check([Some(args.a.as_path()), Some(args.b.as_path())], &outputs)?;
    let (cal_a, a) = args.setting.camera_of(&args.a)?;
    let (cal_b, b) = args.setting.camera_of(&args.b)?;
    if cal_a.image_size != cal_b.image_size {
        return Err(Error::invalid(
            "B.json",
            format!(
                "{} is for {} x {} px and {} for {} x {} px: the same image is compared",
                args.a.display(),
                cal_a.image_size[0],
                cal_a.image_size[1],
                args.b.display(),
                cal_b.image_size[0],
                cal_b.image_size[1]
            ),
        ));
    }
    let d = projection_diff(&a, &b, cal_a.image_size, args.grid)?;
    if let Some(path) = &args.heatmap {
        let cell_px = (640 / args.grid[0].max(1)).clamp(1, 32) as u32;
        let max = if d.rotated_max_px > 0.0 { d.rotated_max_px } else { 1.0 };
        let png = etl_report::heat_map::heat_map_png(&d.rotated_diff_px, d.grid[0], d.grid[1], max, cell_px)?;
        crate::output::create_parent(path)?;
        etl_formats::write_atomic(path, &png)?;
    }
    if args.json {
        let mut j = args.setting.json(&b);
        j["a"] = json!(args.a.display().to_string());
        j["b"] = json!(args.b.display().to_string());
        j["extrapolated"] = json!(a.extrapolated() || b.extrapolated());
        j["grid"] = json!(d.grid);
        j["rms_px"] = json!(d.rms_px);
        j["max_px"] = json!(d.max_px);
        j["rotated_rms_px"] = json!(d.rotated_rms_px);
        j["rotated_max_px"] = json!(d.rotated_max_px);
        j["rotation_rodrigues"] = json!(d.rotation_rodrigues);
        j["unmapped"] = json!(d.unmapped);
        j["heatmap"] = json!(args.heatmap.as_ref().map(|p| p.display().to_string()));
        print_json(&j);
    } else {
        outln!(
            "{} against {} at {} over {}x{} pixels: intrinsics only rms {:.4} px, max {:.4} px; \
             after the best rotation rms {:.4} px, max {:.4} px{}",
            args.b.display(),
            args.a.display(),
            etl_formats::setting_label(&b),
            d.grid[0],
            d.grid[1],
            d.rms_px,
            d.max_px,
            d.rotated_rms_px,
            d.rotated_max_px,
            if d.unmapped > 0 { format!(" ({} pixels did not map)", d.unmapped) } else { String::new() }
        );
    }
    Ok(())
}
