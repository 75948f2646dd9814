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
//!   rename); files of one run in several places by [`write_file_set`] (renamed last,
//!   made one step by a journal that readers complete: crates/etl-formats/src/output/file_set.rs). A
//!   set of files in one directory swapped in whole is the `etlcal` binary's (its
//!   `output::write_dir_set`, built on [`resolve_output`], [`temp_sibling`],
//!   [`remove_stale_temps`] and [`kept_permissions`]): the atomic exchange of two
//!   directories is a Linux system call, and this crate builds wherever `std` does.
//! - Temporaries are named `.NAME.tmpPID` (NAME cut and hashed when the whole would pass
//!   255 bytes, [`temp_stem`]); one whose process is gone is removed by the next run writing
//!   NAME, and so are nested ones that earlier versions left (`..NAME.tmpA.tmpB`). A writer
//!   given its own process's temporary (by [`write_file_set`]) writes it in place.
//!
//! Portability: the policy is written for Unix and holds there whole. Elsewhere it falls
//! back on what `std` offers, and says so: an output is the same file as an input when
//! their canonical paths are equal (symlinks resolved; a hard link is not recognised, as
//! it is on Unix by device and inode); a replaced file keeps its read-only flag (on Unix
//! its permission bits); a temporary of another process is never taken for stale (Linux
//! asks `/proc`), so it is left in place.

use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// An output of a verb, as [`check_paths`] checks it.
#[derive(Clone, Copy, Debug)]
pub enum Output<'a> {
    /// A file, replaced whole.
    File(&'a Path),
    /// A directory holding a set of files, replaced whole (the `etlcal` binary's
    /// `output::write_dir_set`).
    Dir(&'a Path),
}

/// An output the policy refuses: an [`Error::Output`] on `path` whose OS error (of kind
/// `InvalidInput`) says `why`, e.g. `"is read-only: refused as an output"`.
pub fn refused(path: &Path, why: &str) -> Error {
    Error::Output { path: path.to_owned(), source: std::io::Error::new(std::io::ErrorKind::InvalidInput, why) }
}

/// What makes two existing paths one file: device and inode on Unix (hard links and
/// symlinks included); elsewhere `None`, and [`check_paths`] compares canonical paths only
/// (module doc, "Portability").
fn file_id(m: &std::fs::Metadata) -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = m;
        None
    }
}

/// Refuses, before anything is read, inputs that are not regular files and outputs that
/// would destroy an input or a non-file (module doc). Missing inputs are left to their
/// reader (which names them); missing outputs are fine.
pub fn check_paths(inputs: &[&Path], outputs: &[Output<'_>]) -> Result<()> {
    let mut ins = Vec::with_capacity(inputs.len());
    for &p in inputs {
        if let Some(m) = check_input(p)? {
            ins.push((p, file_id(&m), p.canonicalize().unwrap_or_else(|_| p.to_owned())));
        }
    }
    // Each output seen: its file identity (None if it does not exist yet) and its path.
    let mut seen: Vec<(Option<(u64, u64)>, PathBuf)> = Vec::new();
    for out in outputs {
        let (path, is_dir) = match *out {
            Output::File(p) => (p, false),
            Output::Dir(p) => (p, true),
        };
        let Some(m) = existing(path)? else {
            let lexical = absolute(path);
            if seen.iter().any(|(_, s)| *s == lexical) {
                return Err(refused(path, "is given as two outputs"));
            }
            seen.push((None, lexical));
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
        let id = file_id(&m);
        for (input, input_id, input_canonical) in &ins {
            let same = (id.is_some() && *input_id == id) || *input_canonical == canonical;
            if same || (is_dir && input_canonical.starts_with(&canonical)) {
                let what = if same { "is" } else { "holds" };
                return Err(refused(path, &format!("{what} the input {}: refused as an output", input.display())));
            }
        }
        if seen.iter().any(|(i, s)| (id.is_some() && *i == id) || *s == canonical) {
            return Err(refused(path, "is given as two outputs"));
        }
        seen.push((id, canonical));
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

/// The path a write to `path` replaces: the target of a symlink (policy: written through;
/// a dangling one is refused), else `path`; with its directory (`.` for a bare name) and
/// file name. Errors: a path with no file name (`/`, `..`).
pub fn resolve_output(path: &Path) -> Result<(PathBuf, PathBuf, std::ffi::OsString)> {
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            existing(path)?;
            path.canonicalize().map_err(|source| Error::Output { path: path.to_owned(), source })?
        }
        _ => path.components().collect(),
    };
    let name = target
        .file_name()
        .ok_or_else(|| Error::invalid_value("output", path, format!("{}: not a file path", path.display())))?
        .to_owned();
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    Ok((target, dir, name))
}

/// The temporary sibling of `name` in `dir` for this process: `.NAME.tmpPID`.
pub fn temp_sibling(dir: &Path, name: &std::ffi::OsStr) -> PathBuf {
    temp_of(dir, name, std::process::id())
}

/// The longest file name most file systems take, bytes (ext4, XFS, Btrfs, tmpfs).
pub const MAX_NAME_BYTES: usize = 255;

/// The temporary sibling of `name` in `dir` for process `pid`: `.NAME.tmpPID`, with NAME
/// replaced by its [`temp_stem`] when the whole would not fit in [`MAX_NAME_BYTES`].
pub(crate) fn temp_of(dir: &Path, name: &std::ffi::OsStr, pid: u32) -> PathBuf {
    dir.join(format!(".{}.tmp{}", temp_stem(name), pid))
}

/// What a temporary (or a file set's marker) of `name` is named after: `name` itself when
/// `.NAME` and the longer of the two suffixes, `.etlcal-pending` and `.tmp` with a pid of
/// 10 digits (a process id is below 2^32), fit in [`MAX_NAME_BYTES`]; else its first bytes
/// (cut at a character boundary), `~` and 16 hex digits of a hash of the whole name, so
/// that two long names sharing their first bytes still get two temporaries.
pub fn temp_stem(name: &std::ffi::OsStr) -> String {
    let name = name.to_string_lossy();
    let room = MAX_NAME_BYTES - ".".len() - ".etlcal-pending".len();
    if name.len() <= room {
        return name.into_owned();
    }
    // FNV-1a: stable across runs and builds, which std's hasher does not promise.
    let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    let mut cut = room - 17;
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    format!("{}~{hash:016x}", &name[..cut])
}

/// Whether `path` is this process's own temporary (`.NAME.tmpPID`, PID this one's): a
/// writer handed such a path by [`write_file_set`] writes it in place, with no temporary of
/// its own (a temporary of a temporary was left as `..NAME.tmpPID.tmpPID` by a kill).
pub(crate) fn is_own_temp(path: &Path) -> bool {
    let own = format!(".tmp{}", std::process::id());
    path.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with('.') && n.ends_with(&own))
}

/// The process ids of a temporary of `name` called `file_name`: one for `.NAME.tmpPID`,
/// one per level for the nested temporaries earlier versions left (`..NAME.tmpA.tmpB`);
/// `None` when `file_name` is not one.
fn temp_pids<'a>(file_name: &'a str, stem: &str) -> Option<Vec<&'a str>> {
    let depth = file_name.bytes().take_while(|&b| b == b'.').count();
    let rest = file_name.get(depth..)?.strip_prefix(stem)?;
    let pids: Vec<&str> = rest.split(".tmp").skip(1).collect();
    let well_formed =
        rest.starts_with(".tmp") && pids.iter().all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
    (depth >= 1 && pids.len() == depth && well_formed).then_some(pids)
}

/// Removes the temporaries `.NAME.tmpPID` (files or directories) in `dir` left by
/// processes that no longer run (a killed run), nested ones (`..NAME.tmpA.tmpB`) included;
/// best effort, errors ignored. Another running process's temporary is left alone.
///
/// A file set of a killed run pending on `dir/name` ([`write_file_set`]) is completed or
/// abandoned first: its temporaries are either the set's new files or garbage.
pub fn remove_stale_temps(dir: &Path, name: &std::ffi::OsStr) {
    let _ = file_set::complete_pending(&dir.join(name));
    let stem = temp_stem(name);
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pids) = file_name.to_str().and_then(|n| temp_pids(n, &stem)) else { continue };
        if pids.iter().any(|pid| process_runs(pid)) {
            continue;
        }
        let p = entry.path();
        let _ = match entry.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(&p),
            _ => std::fs::remove_file(&p),
        };
    }
}

/// Whether the process `pid` (decimal) runs: this one does; another one when `/proc/PID`
/// exists (Linux); elsewhere every process is taken as running (its temporary is kept).
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
    std::fs::metadata(target).ok().filter(|m| m.is_file()).map(|m| kept_permissions(&m))
}

/// The permissions a replacement of the file or directory of metadata `m` gets: on Unix
/// its permission bits (set-id and sticky bits included, the file type left out);
/// elsewhere its read-only flag (module doc, "Portability").
pub fn kept_permissions(m: &std::fs::Metadata) -> std::fs::Permissions {
    #[cfg(unix)]
    {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        std::fs::Permissions::from_mode(m.mode() & 0o7777)
    }
    #[cfg(not(unix))]
    {
        m.permissions()
    }
}

/// The time a report says it was written, from the environment's `SOURCE_DATE_EPOCH`
/// (reproducible-builds.org: whole seconds since 1970-01-01 UTC), so that two runs on the
/// same inputs write the same bytes; `None` when it is unset (the clock's time is used).
/// A value that is not a whole number of seconds in 0..=253402300799 (year 9999) is
/// refused, as the convention asks, rather than replaced by the clock.
pub fn source_date_epoch() -> Result<Option<i64>> {
    const LAST_S: i64 = 253_402_300_799;
    let Some(raw) = std::env::var_os("SOURCE_DATE_EPOCH") else { return Ok(None) };
    let text = raw.to_string_lossy();
    match text.parse::<i64>() {
        Ok(s) if (0..=LAST_S).contains(&s) && text.bytes().all(|b| b.is_ascii_digit()) => Ok(Some(s)),
        _ => Err(Error::invalid_value(
            "SOURCE_DATE_EPOCH",
            text.as_ref(),
            format!("SOURCE_DATE_EPOCH {text:?} must be whole seconds since 1970 (0..={LAST_S}), or unset"),
        )),
    }
}

mod file_set;
pub(crate) use file_set::write_synced;
pub use file_set::{write_bytes_set, write_file_set};

// The policy's tests make symlinks, hard links, FIFOs and modes: Unix only.
#[cfg(all(test, unix))]
mod tests;
