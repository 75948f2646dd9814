//! A set of files in one directory, replaced whole (docs/RELIABILITY.md, "Outputs"): the
//! outputs of `simulate`, `report` and `demo`. It lives in the binary, not in
//! etl_formats::output (the rest of the policy, which it builds on), because the atomic
//! exchange of two directories is a Linux system call (`renameat2(RENAME_EXCHANGE)`,
//! through `nix`) and etl-formats builds wherever `std` does.

use std::path::Path;

use etl_formats::output::Output;
use etl_formats::output::{check_paths, kept_permissions, refused, remove_stale_temps, resolve_output, temp_sibling};
use etl_formats::{write_atomic, Error, Result};

/// The file listing a set directory's top-level entries (one per line), written last into
/// every set; entries it names may be replaced by the next set.
pub const SET_MANIFEST: &str = ".etlcal-set";

/// Writes a set of files into the directory `dir` as one: `write` fills a fresh temporary
/// sibling directory (`.NAME.tmpPID`), which then takes `dir`'s place in one atomic
/// exchange (Linux `renameat2(RENAME_EXCHANGE)`; elsewhere two renames, see `swap_in`),
/// and the earlier set is removed. A kill or an error at any moment leaves `dir` with the
/// whole earlier set or the whole new one; on error the temporary directory is removed.
///
/// Preconditions (refused before `write` runs): `dir`, if it exists, is a directory whose
/// entries all belong to etlcal's sets (named in its [`SET_MANIFEST`] or in `set_names`,
/// the top-level names this set writes): a file of the user's is never thrown away.
/// `write` gets the temporary directory and returns its value; paths it reports under the
/// temporary directory are the caller's to map onto `dir` ([`super::moved`]).
pub fn write_dir_set<T>(dir: &Path, set_names: &[&str], write: impl FnOnce(&Path) -> Result<T>) -> Result<T> {
    let (target, parent, name) = resolve_output(dir)?;
    if target.parent().is_none() || name == "." || name == ".." {
        return Err(refused(dir, "cannot be replaced as a set (a root or relative directory name)"));
    }
    std::fs::create_dir_all(&parent).map_err(|source| Error::Output { path: parent.clone(), source })?;
    // A dangling symlink or a non-directory at `dir` is refused here, as every output is.
    check_paths(&[], &[Output::Dir(dir)])?;
    let old = std::fs::metadata(&target).ok();
    if old.is_some() {
        refuse_foreign_entries(dir, &target, set_names)?;
    }
    remove_stale_temps(&parent, &name);
    let staging = temp_sibling(&parent, &name);
    let _ = std::fs::remove_dir_all(&staging);
    let io = |source| Error::Output { path: dir.to_owned(), source };
    std::fs::create_dir(&staging).map_err(io)?;
    let result = write(&staging).and_then(|value| {
        let entries = top_level_names(&staging).map_err(io)?;
        write_atomic(&staging.join(SET_MANIFEST), (entries.join("\n") + "\n").as_bytes())?;
        if let Some(m) = &old {
            std::fs::set_permissions(&staging, kept_permissions(m)).map_err(io)?;
        }
        sync_dir(&staging).map_err(io)?;
        swap_in(&staging, &target, old.is_some()).map_err(io)?;
        Ok(value)
    });
    // After a swap the earlier set is at the temporary name; on error the partial new one.
    let _ = std::fs::remove_dir_all(&staging);
    result
}

/// Flushes the directory `dir`'s entries to disk (Unix: `fsync` of the directory); a
/// no-op where a directory cannot be opened as a file.
fn sync_dir(dir: &Path) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        std::fs::File::open(dir).and_then(|f| f.sync_all())
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        Ok(())
    }
}

/// Puts `staging` in the place of `target`: an atomic exchange when `target` exists.
fn swap_in(staging: &Path, target: &Path, exists: bool) -> std::io::Result<()> {
    if !exists {
        return std::fs::rename(staging, target);
    }
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let cwd = std::fs::File::open(".")?;
        nix::fcntl::renameat2(&cwd, staging, &cwd, target, nix::fcntl::RenameFlags::RENAME_EXCHANGE)
            .map_err(std::io::Error::from)
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        // No atomic exchange here: the earlier set is moved aside first (a kill between the
        // two renames leaves it at `.NAME.old`, whole).
        let aside = staging.with_extension("old");
        std::fs::rename(target, &aside)?;
        std::fs::rename(staging, target)?;
        std::fs::rename(&aside, staging)
    }
}

/// The sorted top-level entry names of `dir`.
fn top_level_names(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        names.push(entry?.file_name().to_string_lossy().into_owned());
    }
    names.sort();
    Ok(names)
}

/// Refuses a set directory holding an entry that is neither in its manifest nor in
/// `set_names` (nor a manifest): the user's file, which a swap would throw away.
fn refuse_foreign_entries(dir: &Path, target: &Path, set_names: &[&str]) -> Result<()> {
    let manifest = std::fs::read_to_string(target.join(SET_MANIFEST)).unwrap_or_default();
    let known = |n: &str| n == SET_MANIFEST || set_names.contains(&n) || manifest.lines().any(|l| l == n);
    let names = top_level_names(target).map_err(|source| Error::Output { path: dir.to_owned(), source })?;
    match names.iter().find(|n| !known(n)) {
        Some(n) => Err(refused(
            dir,
            &format!(
                "holds {n}, which is not an etlcal output: the set is replaced whole; pass a new or empty directory"
            ),
        )),
        None => Ok(()),
    }
}

#[cfg(all(test, unix))]
mod tests;
