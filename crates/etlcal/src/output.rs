//! Output paths, one rule for every verb: a missing output directory is created (with any
//! missing parents, as `mkdir -p`), and so is the missing parent directory of an output
//! file. A path that exists but is not a directory is refused by the operating system.

use std::path::Path;

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
