//! `etlcal sharpness IMAGE... --metric cpbd|tenengrad|laplacian|brenner|normvar [--json]`:
//! the sharpness of each image (`{"images": [{"path", "value"}]}` with `--json`, else one
//! `path<TAB>value` line per image).
//!
//! Images are decoded by the `image` crate (PNG, JPEG, TIFF). 8-bit grayscale is measured
//! as is, 16-bit grayscale as described in `sharpness`, colour images after conversion to
//! luminance (the `image` crate's `to_luma8`/`to_luma16`; the reference CPBD package does
//! no colour conversion and must be given the same gray image to agree). An unreadable,
//! corrupt or too small image fails the whole command, naming the file.

use std::path::PathBuf;

use rayon::prelude::*;
use serde_json::json;

use super::print_json;
use etl_formats::Result;
use etl_image::sharpness::{sharpness_file, Metric};

/// Arguments of `etlcal sharpness`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The images (PNG, JPEG or TIFF; 8- or 16-bit).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// The measure: cpbd, tenengrad, laplacian, brenner or normvar.
    #[arg(long, value_parser = parse_metric, default_value = "cpbd")]
    pub metric: Metric,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

fn parse_metric(s: &str) -> std::result::Result<Metric, String> {
    s.parse::<Metric>().map_err(|e| e.to_string())
}

/// Runs `etlcal sharpness`.
pub fn run(args: Args) -> Result<()> {
    let values: Vec<f64> =
        args.images.par_iter().map(|p| sharpness_file(p, args.metric)).collect::<Result<Vec<f64>>>()?;
    if args.json {
        let images: Vec<_> = args
            .images
            .iter()
            .zip(&values)
            .map(|(p, v)| json!({"path": p.display().to_string(), "value": v}))
            .collect();
        print_json(&json!({"metric": args.metric.name(), "images": images}));
    } else {
        for (p, v) in args.images.iter().zip(&values) {
            outln!("{}\t{v}", p.display());
        }
    }
    Ok(())
}
