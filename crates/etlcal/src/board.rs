//! `etlcal board --board FILE --out board.svg|board.png [--dpi N] [--margin-mm M]
//! [--json]`: the print-ready target of an `etlcal.board/1` file ([`etl_sim::print`]): an
//! SVG whose `width`/`height` are in mm (it prints at true size at 100 % scale) or a PNG
//! rendered exactly at `--dpi` (default 600) that records its resolution; a white margin
//! of `--margin-mm` (default: one square) around the pattern. Any other extension is
//! refused before anything is read or written; the file is written atomically (its
//! directory created if missing). `--json`: `{"out", "board", "width_mm", "height_mm",
//! "margin_mm"}`, with `"dpi", "width_px", "height_px"` for a PNG.
//!
//! Also the board flags shared by the verbs that look for a board in images (`zhang`,
//! `measure`): `--pattern CxR --square MM` or `--board FILE`.

use std::path::PathBuf;

use etl_formats::board::Board;
use etl_formats::output::Output;
use etl_formats::{check_range, compact, write_atomic, Error, Result};
use etl_sim::print;
use serde_json::json;

/// Parses a pattern `CxR` (inner corners, columns x rows), e.g. `14x12`.
pub fn parse_pattern(s: &str) -> std::result::Result<[usize; 2], String> {
    let (c, r) = s.split_once(['x', 'X']).ok_or_else(|| format!("pattern \"{s}\" is not CxR (e.g. 14x12)"))?;
    let parse = |t: &str| t.trim().parse::<usize>().map_err(|_| format!("pattern \"{s}\" is not CxR (e.g. 14x12)"));
    Ok([parse(c)?, parse(r)?])
}

/// `--pattern CxR --square MM` (a whole checkerboard) or `--board FILE` (an
/// `etlcal.board/1` file: a ChArUco board, found in part too, or a checkerboard).
#[derive(clap::Args, Debug, Clone)]
pub struct BoardArgs {
    /// Inner corners of a checkerboard, columns x rows (e.g. 14x12); with --square.
    #[arg(long, value_parser = parse_pattern, requires = "square", required_unless_present = "board")]
    pub pattern: Option<[usize; 2]>,
    /// Side of a square of the --pattern checkerboard, mm.
    #[arg(long, value_name = "MM", requires = "pattern")]
    pub square: Option<f64>,
    /// The board, an etlcal.board/1 file (ChArUco or checkerboard), instead of --pattern
    /// and --square.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["pattern", "square"])]
    pub board: Option<PathBuf>,
}

impl BoardArgs {
    /// The board the flags describe (read from its file); an error names the flags.
    pub fn board(&self) -> etl_formats::Result<Board> {
        if let Some(path) = &self.board {
            return Board::load(path);
        }
        let (Some(pattern), Some(square)) = (self.pattern, self.square) else {
            return Err(Error::invalid("--board", "give --board FILE, or --pattern CxR with --square MM"));
        };
        let [c, r] = pattern;
        Board::checkerboard(pattern, square).map_err(|e| {
            let flag = if e.input_what() == Some("square_mm") { "--square" } else { "--pattern" };
            e.within(format!("--pattern {c}x{r} --square {square}"), None).map_what(|_| flag.to_owned())
        })
    }

    /// The board file, if any (an input the verb's outputs must not overwrite).
    pub fn file(&self) -> Option<&std::path::Path> {
        self.board.as_deref()
    }
}

/// Arguments of `etlcal board`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The board, an etlcal.board/1 file (ChArUco or checkerboard).
    #[arg(long, value_name = "FILE")]
    pub board: PathBuf,
    /// The file to write: .svg (sizes in mm: print at 100 %) or .png (at --dpi); its
    /// directory is created if missing.
    #[arg(long, value_name = "board.svg|board.png")]
    pub out: PathBuf,
    /// Resolution of a PNG, dots per inch [default: 600]; not for an SVG (sized in mm).
    #[arg(long, value_name = "N")]
    pub dpi: Option<f64>,
    /// White margin around the pattern, mm [default: one square].
    #[arg(long, value_name = "M")]
    pub margin_mm: Option<f64>,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The resolution of a PNG when `--dpi` is not given.
pub const DEFAULT_DPI: f64 = 600.0;

/// Runs `etlcal board`.
pub fn run(args: Args) -> Result<()> {
    let ext = args.out.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let png = match ext.as_str() {
        "svg" => false,
        "png" => true,
        _ => {
            let message = format!(
                "{}: unsupported extension \"{ext}\": use .svg (true size in mm) or .png (at --dpi)",
                args.out.display()
            );
            return Err(Error::invalid_value("--out", args.out.as_path(), message));
        }
    };
    if let (false, Some(d)) = (png, args.dpi) {
        let message = format!("--dpi {} applies to a .png only (an SVG is sized in mm)", compact(d));
        return Err(Error::invalid_value("--dpi", d, message));
    }
    let dpi = check_range("--dpi", args.dpi.unwrap_or(DEFAULT_DPI), print::DPI_RANGE, "dpi")?;
    if let Some(m) = args.margin_mm {
        check_range("--margin-mm", m, [0.0, print::MAX_MARGIN_MM], "mm")?;
    }
    crate::output::check([Some(args.board.as_path())], &[Output::File(&args.out)])?;
    let board = Board::load(&args.board)?;
    let margin_mm = args.margin_mm.unwrap_or(board.square_mm());
    let [width_mm, height_mm] = print::page_mm(&board, margin_mm);
    let mut report = json!({"out": args.out, "board": board, "width_mm": width_mm, "height_mm": height_mm,
        "margin_mm": margin_mm});
    let bytes = if png {
        let image = print::raster(&board, dpi, margin_mm)?;
        report["dpi"] = json!(dpi);
        report["width_px"] = json!(image.width);
        report["height_px"] = json!(image.height);
        print::encode_png(&image, dpi)?
    } else {
        print::svg(&board, margin_mm)?.into_bytes()
    };
    crate::output::create_parent(&args.out)?;
    write_atomic(&args.out, &bytes)?;
    if args.json {
        super::print_json(&report);
    } else {
        let at = if png { format!(" at {} dpi", compact(dpi)) } else { String::new() };
        outln!(
            "wrote {}{at}: {}, page {} x {} mm (margin {} mm); print at 100 % (no scaling)",
            args.out.display(),
            board.describe(),
            compact(width_mm),
            compact(height_mm),
            compact(margin_mm)
        );
    }
    Ok(())
}
