//! Where etlcal writes, one policy for every writer (docs/RELIABILITY.md, "Outputs"):
//!
//! - [`check_paths`] is run by a verb before it reads anything: an input must be a
//!   regular file (a FIFO would block, a device would stream); an output that exists must
//!   be a regular file (a file output) or a directory (a directory output), must not be an
//!   input (same device and inode: hard links and symlinks included), must not hold an
//!   input (a directory output), and must not be written twice.
//! - A symlink as an output is written through: the file it resolves to is replaced and
//!   the link kept; a dangling symlink is refused.
//! - A replaced file keeps its permission bits; a read-only file is refused.
//! - One file is written atomically by [`crate::write_atomic`] (a temporary sibling, then a
//!   rename); a set of files in one directory by [`write_dir_set`] (a temporary sibling
//!   directory, then an atomic exchange), so a kill leaves the earlier set or the new one.
//! - Temporaries are named `.NAME.tmpPID`; one whose process is gone is removed by the next
//!   run writing NAME.

use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// The file listing a set directory's top-level entries (one per line), written last into
/// every set; entries it names may be replaced by the next set.
pub const SET_MANIFEST: &str = ".etlcal-set";

/// An output of a verb, as [`check_paths`] checks it.
#[derive(Clone, Copy, Debug)]
pub enum Output<'a> {
    /// A file, replaced whole.
    File(&'a Path),
    /// A directory holding a set of files, replaced whole ([`write_dir_set`]).
    Dir(&'a Path),
}

fn refused(path: &Path, why: &str) -> Error {
    Error::Output { path: path.to_owned(), source: std::io::Error::new(std::io::ErrorKind::InvalidInput, why) }
}

/// Refuses, before anything is read, inputs that are not regular files and outputs that
/// would destroy an input or a non-file (module doc). Missing inputs are left to their
/// reader (which names them); missing outputs are fine.
pub fn check_paths(inputs: &[&Path], outputs: &[Output<'_>]) -> Result<()> {
    let mut ins = Vec::with_capacity(inputs.len());
    for &p in inputs {
        if let Some(m) = check_input(p)? {
            ins.push((p, m.dev(), m.ino(), p.canonicalize().unwrap_or_else(|_| p.to_owned())));
        }
    }
    let mut seen: Vec<(u64, u64, PathBuf)> = Vec::new();
    for out in outputs {
        let (path, is_dir) = match *out {
            Output::File(p) => (p, false),
            Output::Dir(p) => (p, true),
        };
        let Some(m) = existing(path)? else {
            let lexical = absolute(path);
            if seen.iter().any(|(_, _, s)| *s == lexical) {
                return Err(refused(path, "is given as two outputs"));
            }
            seen.push((0, 0, lexical));
            continue;
        };
        if is_dir && !m.is_dir() {
            return Err(refused(path, "exists and is not a directory (a directory output)"));
        }
        if !is_dir && !m.file_type().is_file() {
            return Err(refused(path, "exists and is not a regular file: refused as an output"));
        }
        if !is_dir && m.permissions().readonly() {
            return Err(refused(path, "is read-only: refused as an output"));
        }
        let canonical = path.canonicalize().map_err(|source| Error::Output { path: path.to_owned(), source })?;
        for (input, dev, ino, input_canonical) in &ins {
            let same = (*dev, *ino) == (m.dev(), m.ino());
            if same || (is_dir && input_canonical.starts_with(&canonical)) {
                let what = if same { "is" } else { "holds" };
                return Err(refused(path, &format!("{what} the input {}: refused as an output", input.display())));
            }
        }
        if seen.iter().any(|(d, i, s)| (*d, *i) == (m.dev(), m.ino()) || *s == canonical) {
            return Err(refused(path, "is given as two outputs"));
        }
        seen.push((m.dev(), m.ino(), canonical));
    }
    Ok(())
}

/// `path` with its existing directory made canonical, for comparing outputs that do not
/// exist yet (`t.json` and `./t.json` are one file).
pub(crate) fn absolute(path: &Path) -> PathBuf {
    let lexical: PathBuf = path.components().collect();
    let dir = match lexical.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (dir.canonicalize(), lexical.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => lexical,
    }
}

/// The metadata of the input `path` (symlinks followed), refusing anything but a regular
/// file; `None` when it does not exist.
///
/// A set of files that a killed run left half renamed ([`write_file_set`]) is completed
/// first, so that the input read is the set's new file, never a mix of two runs.
pub fn check_input(path: &Path) -> Result<Option<std::fs::Metadata>> {
    file_set::complete_pending(path)?;
    match std::fs::metadata(path) {
        Ok(m) if m.file_type().is_file() => Ok(Some(m)),
        Ok(_) => Err(Error::Io {
            path: path.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a regular file: refused as an input"),
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(Error::Io { path: path.to_owned(), source }),
    }
}

/// The metadata of the output `path` with symlinks followed, `None` when nothing is there;
/// a dangling symlink is refused (writing would create a file somewhere unexpected).
fn existing(path: &Path) -> Result<Option<std::fs::Metadata>> {
    match std::fs::metadata(path) {
        Ok(m) => Ok(Some(m)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if std::fs::symlink_metadata(path).is_ok() {
                return Err(refused(path, "is a dangling symbolic link: refused as an output"));
            }
            Ok(None)
        }
        Err(source) => Err(Error::Output { path: path.to_owned(), source }),
    }
}

/// The path a write to `path` replaces: the target of a symlink (policy: written through),
/// else `path`; with its directory (`.` for a bare name) and file name.
pub(crate) fn resolve_output(path: &Path) -> Result<(PathBuf, PathBuf, std::ffi::OsString)> {
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            existing(path)?;
            path.canonicalize().map_err(|source| Error::Output { path: path.to_owned(), source })?
        }
        _ => path.components().collect(),
    };
    let name = target
        .file_name()
        .ok_or_else(|| Error::InvalidInput(format!("{}: not a file path", path.display())))?
        .to_owned();
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    Ok((target, dir, name))
}

/// The temporary sibling of `name` in `dir` for this process: `.NAME.tmpPID`.
pub(crate) fn temp_sibling(dir: &Path, name: &std::ffi::OsStr) -> PathBuf {
    temp_of(dir, name, std::process::id())
}

/// The temporary sibling of `name` in `dir` for process `pid`: `.NAME.tmpPID`.
pub(crate) fn temp_of(dir: &Path, name: &std::ffi::OsStr, pid: u32) -> PathBuf {
    dir.join(format!(".{}.tmp{}", name.to_string_lossy(), pid))
}

/// Removes the temporaries `.NAME.tmpPID` (files or directories) in `dir` left by
/// processes that no longer run (a killed run); best effort, errors ignored. Another
/// running process's temporary is left alone.
///
/// A file set of a killed run pending on `dir/name` ([`write_file_set`]) is completed or
/// abandoned first: its temporaries are either the set's new files or garbage.
pub(crate) fn remove_stale_temps(dir: &Path, name: &std::ffi::OsStr) {
    let _ = file_set::complete_pending(&dir.join(name));
    let prefix = format!(".{}.tmp", name.to_string_lossy());
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name.to_str().and_then(|n| n.strip_prefix(&prefix)) else { continue };
        if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) || process_runs(pid) {
            continue;
        }
        let p = entry.path();
        let _ = match entry.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(&p),
            _ => std::fs::remove_file(&p),
        };
    }
}

/// Whether the process `pid` (decimal) runs: `/proc/PID` exists (Linux); elsewhere every
/// process but this one is taken as gone only if it is not this one.
pub(crate) fn process_runs(pid: &str) -> bool {
    if pid == std::process::id().to_string() {
        return true;
    }
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid).exists()
    } else {
        true
    }
}

/// The permission bits of the regular file the write to `target` replaces, if any.
pub(crate) fn kept_mode(target: &Path) -> Option<std::fs::Permissions> {
    std::fs::metadata(target).ok().filter(|m| m.is_file()).map(|m| std::fs::Permissions::from_mode(m.mode() & 0o7777))
}

/// Writes a set of files into the directory `dir` as one: `write` fills a fresh temporary
/// sibling directory (`.NAME.tmpPID`), which then takes `dir`'s place in one atomic
/// exchange (Linux `renameat2(RENAME_EXCHANGE)`), and the earlier set is removed. A kill
/// or an error at any moment leaves `dir` with the whole earlier set or the whole new one;
/// on error the temporary directory is removed.
///
/// Preconditions (refused before `write` runs): `dir`, if it exists, is a directory whose
/// entries all belong to etlcal's sets (named in its [`SET_MANIFEST`] or in `set_names`,
/// the top-level names this set writes): a file of the user's is never thrown away.
/// `write` gets the temporary directory and returns its value; paths it reports under the
/// temporary directory are the caller's to map onto `dir`.
pub fn write_dir_set<T>(dir: &Path, set_names: &[&str], write: impl FnOnce(&Path) -> Result<T>) -> Result<T> {
    let (target, parent, name) = resolve_output(dir)?;
    if target.parent().is_none() || name == "." || name == ".." {
        return Err(refused(dir, "cannot be replaced as a set (a root or relative directory name)"));
    }
    std::fs::create_dir_all(&parent).map_err(|source| Error::Output { path: parent.clone(), source })?;
    let old = existing(&target)?;
    if let Some(m) = &old {
        if !m.is_dir() {
            return Err(refused(dir, "exists and is not a directory (a directory output)"));
        }
        refuse_foreign_entries(dir, &target, set_names)?;
    }
    remove_stale_temps(&parent, &name);
    let staging = temp_sibling(&parent, &name);
    let _ = std::fs::remove_dir_all(&staging);
    let io = |source| Error::Output { path: dir.to_owned(), source };
    std::fs::create_dir(&staging).map_err(io)?;
    let result = write(&staging).and_then(|value| {
        let entries = top_level_names(&staging).map_err(io)?;
        crate::write_atomic(&staging.join(SET_MANIFEST), (entries.join("\n") + "\n").as_bytes())?;
        if let Some(m) = &old {
            let mode = std::fs::Permissions::from_mode(m.mode() & 0o7777);
            std::fs::set_permissions(&staging, mode).map_err(io)?;
        }
        std::fs::File::open(&staging).and_then(|f| f.sync_all()).map_err(io)?;
        swap_in(&staging, &target, old.is_some()).map_err(io)?;
        Ok(value)
    });
    // After a swap the earlier set is at the temporary name; on error the partial new one.
    let _ = std::fs::remove_dir_all(&staging);
    result
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

mod file_set;
pub use file_set::write_file_set;

#[cfg(test)]
mod tests;
