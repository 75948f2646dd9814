//! Output paths, one rule for every verb: a missing output directory is created (with any
//! missing parents, as `mkdir -p`), and so is the missing parent directory of an output
//! file. Before reading anything a verb checks its inputs and outputs with [`check`]
//! (etl_formats::output's policy: an output that is an input, or exists and is not a
//! regular file, is refused); several outputs are written as one set ([`write_dir_set`]
//! for a set in one directory, [`etl_formats::output::write_file_set`] for files in
//! several places).

use std::path::{Path, PathBuf};

mod dir_set;

pub use dir_set::write_dir_set;
pub use etl_formats::output::source_date_epoch;

use etl_formats::output::{check_paths, Output};
use etl_formats::{Error, Result};

/// Creates the directory `dir` and its missing parents; nothing to do when it exists.
pub fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Output { path: dir.to_owned(), source })
}

/// Creates the parent directory of the output file `file` (and its missing parents); a
/// bare file name (parent `""`) is in the working directory, which exists.
pub fn create_parent(file: &Path) -> Result<()> {
    match file.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(dir) => create_dir(dir),
        None => Ok(()),
    }
}

/// The file of a `--thermal FILE|paper` flag: `None` for `paper` (no file).
pub fn thermal_file(choice: Option<&Path>) -> Option<&Path> {
    choice.filter(|p| *p != Path::new(etl_formats::calibration::PAPER_THERMAL))
}

/// [`check_paths`] over the inputs that were given (`None`s skipped) and the outputs.
pub fn check<'a>(inputs: impl IntoIterator<Item = Option<&'a Path>>, outputs: &[Output<'_>]) -> Result<()> {
    let inputs: Vec<&Path> = inputs.into_iter().flatten().collect();
    check_paths(&inputs, outputs)
}

/// The paths `files` reports under the temporary directory `staging` of a set, as they
/// are once the set is in place at `dir`.
pub fn moved(files: Vec<PathBuf>, staging: &Path, dir: &Path) -> Vec<PathBuf> {
    files.into_iter().map(|f| f.strip_prefix(staging).map(|rel| dir.join(rel)).unwrap_or(f)).collect()
}
