//! `etlcal render --out IMAGE.png [--e-com MA] [--z-mm Z] [--pattern CxR] [--square MM |
//! --board FILE] [--aperture-mm A] [--blur-px S] [--noise DN] [--bit-depth 8|16] [--seed N]
//! [--json]`: one synthetic image of a board on the paper rig's stage seen through the paper
//! rig's camera at a current, and its true corners.
//!
//! Writes IMAGE (8- or 16-bit grayscale, in the format its extension names: `.png`,
//! `.tif`/`.tiff`, or `.jpg`/`.jpeg` for 8-bit only; any other extension is refused before
//! rendering; its directory is created if missing) and, beside it, IMAGE.corners.json:
//! `{"format": "etlcal.corners/1", "pattern": [c, r], "square_mm", "e_com_ma", "z_w_mm",
//! "corners_px": [[u, v], ...], "in_image": [bool, ...], "blur_sigma_px"}`, corners row by
//! row (i fastest) in the order `etlcal detect` reports them. With `--board FILE` (an
//! `etlcal.board/1` file, ChArUco or checkerboard, in place of `--pattern`/`--square`):
//! `{"format": "etlcal.corners/1", "board": {...}, "e_com_ma", "z_w_mm", "ids": [...],
//! "corners_px": [[u, v], ...], "blur_sigma_px"}`, the corners inside the image only, with
//! their ids (as `etlcal detect --board` reports them); the board frame (ChArUco: OpenCV's)
//! is the stage's X, Y. Defocus follows the paper
//! rig's focus at the current (`--aperture-mm`, 0 = none); `--blur-px` adds a uniform blur.
//! Both files are written atomically, and only when the render succeeded.

use std::path::{Path, PathBuf};

use etl_core::model::CameraModel;
use serde_json::json;

use super::print_json;
use etl_formats::board::Board;
use etl_formats::output::{write_file_set, Output};
use etl_formats::{write_atomic, write_json};
use etl_formats::{Error, Result};
use etl_image::checkerboard::Pattern;
use etl_sim::render::{render, BitDepth, PaperRender, Scene};

/// Arguments of `etlcal render`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The image to write: .png, .tif/.tiff, or .jpg/.jpeg (8-bit); its directory is
    /// created if missing.
    #[arg(long, value_name = "IMAGE.png")]
    pub out: PathBuf,
    /// Compensated lens current, mA.
    #[arg(long, default_value_t = 150.0)]
    pub e_com: f64,
    /// Stage position Z_W, mm (default: the paper rig's focus position at the current).
    #[arg(long)]
    pub z_mm: Option<f64>,
    /// Inner corners, columns x rows.
    #[arg(long, default_value = "14x12")]
    pub pattern: Pattern,
    /// Square size, mm.
    #[arg(long, default_value_t = 1.5)]
    pub square: f64,
    /// The board, an etlcal.board/1 file (ChArUco or checkerboard), instead of
    /// --pattern and --square.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["pattern", "square"])]
    pub board: Option<PathBuf>,
    /// Aperture diameter for the defocus, mm (0: no defocus).
    #[arg(long, default_value_t = 2.5)]
    pub aperture_mm: f64,
    /// Additional uniform Gaussian blur, px.
    #[arg(long, default_value_t = 0.0)]
    pub blur_px: f64,
    /// Read noise, grey levels (8-bit scale).
    #[arg(long, default_value_t = 2.0)]
    pub noise: f64,
    /// Bits per pixel: 8 or 16.
    #[arg(long, default_value_t = 8)]
    pub bit_depth: u8,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The CLI's spelling of a [`PaperRender`] key: `--aperture-mm`; the current is `--e-com`.
fn flag(key: &'static str) -> String {
    match key {
        "e_com_ma" => "--e-com".to_owned(),
        key => format!("--{}", key.replace('_', "-")),
    }
}

/// Runs `etlcal render`.
pub fn run(args: Args) -> Result<()> {
    let bit_depth = match args.bit_depth {
        8 => BitDepth::Eight,
        16 => BitDepth::Sixteen,
        b => return Err(Error::invalid_value("--bit-depth", b, format!("--bit-depth must be 8 or 16, got {b}"))),
    };
    let format = image_format(&args.out, bit_depth)?;
    let mut corners_path = args.out.clone().into_os_string();
    corners_path.push(".corners.json");
    let corners_path = PathBuf::from(corners_path);
    crate::output::check([args.board.as_deref()], &[Output::File(&args.out), Output::File(&corners_path)])?;
    let truth = CameraModel::paper_rig();
    let request = PaperRender {
        e_com_ma: args.e_com,
        z_mm: args.z_mm,
        aperture_mm: args.aperture_mm,
        blur_px: args.blur_px,
        noise: args.noise,
        bit_depth,
        seed: args.seed,
    };
    request.validate(flag)?;
    let (e, z) = (request.e_com_ma, request.stage_z_mm());
    let board = match &args.board {
        Some(path) => Board::load(path)?,
        None => Board::checkerboard([args.pattern.cols, args.pattern.rows], args.square)?,
    };
    let scene = Scene::new(truth, e, board, z, CameraModel::PAPER_IMAGE_SIZE);
    let opts = request.options(&truth);
    let r = render(&scene, &opts)?;
    let corners = match args.board {
        Some(_) => {
            let (ids, corners_px) = r.visible();
            json!({"format": "etlcal.corners/1", "board": board, "e_com_ma": e, "z_w_mm": z, "ids": ids,
                "corners_px": corners_px, "blur_sigma_px": r.blur_sigma_px})
        }
        None => json!({
            "format": "etlcal.corners/1",
            "pattern": [args.pattern.cols, args.pattern.rows],
            "square_mm": args.square,
            "e_com_ma": e,
            "z_w_mm": z,
            "corners_px": r.corners_px,
            "in_image": r.corners_in_image,
            "blur_sigma_px": r.blur_sigma_px,
        }),
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
    r.image.to_dynamic().write_to(&mut bytes, format).map_err(|e| Error::Output {
        path: args.out.clone(),
        source: std::io::Error::other(format!("cannot encode: {e}")),
    })?;
    crate::output::create_parent(&args.out)?;
    // The image and its corners, both or neither.
    write_file_set(&[&args.out, &corners_path], |tmp| {
        write_atomic(&tmp[0], bytes.get_ref())?;
        write_json(&tmp[1], &corners)
    })?;
    if args.json {
        print_json(&corners);
    } else {
        outln!(
            "wrote {} ({} x {} px, blur sigma {:.2} px at the board's centre) and its corners",
            args.out.display(),
            scene.image_size[0],
            scene.image_size[1],
            r.blur_sigma_px
        );
    }
    Ok(())
}

/// The image format `path`'s extension names (case-insensitive): PNG, TIFF, or JPEG for
/// 8-bit images (JPEG has no 16-bit grey); anything else is refused, naming the choices.
fn image_format(path: &Path, bit_depth: BitDepth) -> Result<image::ImageFormat> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match (ext.as_str(), bit_depth) {
        ("png", _) => Ok(image::ImageFormat::Png),
        ("tif" | "tiff", _) => Ok(image::ImageFormat::Tiff),
        ("jpg" | "jpeg", BitDepth::Eight) => Ok(image::ImageFormat::Jpeg),
        ("jpg" | "jpeg", BitDepth::Sixteen) => Err(Error::invalid_value(
            "--bit-depth",
            16_u8,
            format!("{}: JPEG is 8-bit only: pass --bit-depth 8 or write .png, .tif or .tiff", path.display()),
        )),
        _ => Err(Error::invalid_value(
            "--out",
            path,
            format!("{}: unsupported image extension \"{ext}\": use .png, .tif, .tiff, .jpg or .jpeg", path.display()),
        )),
    }
}
