//! The board flags shared by the verbs that look for a board in images (`zhang`,
//! `measure`): `--pattern CxR --square MM`.

use etl_formats::board::Board;

/// Parses a pattern `CxR` (inner corners, columns x rows), e.g. `14x12`.
pub fn parse_pattern(s: &str) -> std::result::Result<[usize; 2], String> {
    let (c, r) = s.split_once(['x', 'X']).ok_or_else(|| format!("pattern \"{s}\" is not CxR (e.g. 14x12)"))?;
    let parse = |t: &str| t.trim().parse::<usize>().map_err(|_| format!("pattern \"{s}\" is not CxR (e.g. 14x12)"));
    Ok([parse(c)?, parse(r)?])
}

/// `--pattern CxR --square MM`.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct BoardArgs {
    /// Inner corners, columns x rows (e.g. 14x12).
    #[arg(long, value_parser = parse_pattern)]
    pub pattern: [usize; 2],
    /// Side of a square, mm.
    #[arg(long, value_name = "MM")]
    pub square: f64,
}

impl BoardArgs {
    /// The board the flags describe; an error names the flags.
    pub fn board(&self) -> etl_formats::Result<Board> {
        let [c, r] = self.pattern;
        Board::checkerboard(self.pattern, self.square).map_err(|e| {
            let e = e.to_string();
            let e = e.strip_prefix("invalid input: ").unwrap_or(&e);
            etl_formats::Error::InvalidInput(format!("--pattern {c}x{r} --square {}: {e}", self.square))
        })
    }
}
