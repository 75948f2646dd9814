//! Files of one run in different places, replaced as one set (docs/RELIABILITY.md,
//! "Outputs"): `calibrate --out --observations-out`, `render` (image + corners), `thermal
//! calibrate` (surface + table).
//!
//! No single rename replaces files in several directories, so the renames are made safe
//! by a small journal: before the first rename, every output gets a marker beside it,
//! `.NAME.etlcal-pending`, listing the whole set; the marker of the first output is
//! written last and is the commit. A kill at any moment then leaves one of three states:
//!
//! - no commit: no output was renamed; the outputs are the earlier set, whole. The
//!   markers and temporaries left are garbage, removed by the next reader or writer once
//!   their process is gone.
//! - committed, some renames missing: every new file is complete in its temporary (they
//!   were written and flushed before the markers). The next reader of any output, or the
//!   next writer, sees its marker and finishes the renames before it reads: it reads the
//!   new set, whole.
//! - committed, renamed: the markers are removed (the commit last).
//!
//! Readers find the marker with one `stat` per input ([`super::check_input`]). A power
//! loss is not covered beyond what `fsync` of the files and markers gives; concurrent
//! writers of the same outputs are not supported (as before: the last rename wins).

use std::io::Write;
use std::path::{Path, PathBuf};

use super::{absolute, check_paths, kept_mode, process_runs, remove_stale_temps, resolve_output, temp_of, Output};
use crate::{Error, Result};

/// The first line of a marker (and its version).
const MAGIC: &str = "etlcal-pending 1";

/// The last line of a complete marker: a marker cut by a kill while it was written lacks
/// it and is not a commit.
const END: &str = "end";

/// The steps of the commit, in order, as [`write_file_set_observed`] reports them (a test
/// stops the process at each to check the state it leaves).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Step {
    /// Every new file is written to its temporary.
    Written,
    /// The marker of output `k` (k >= 1) is written.
    Marked(usize),
    /// The commit (the marker of output 0) is written.
    Committed,
    /// Output `k` is renamed into place.
    Renamed(usize),
    /// The marker of output `k` is removed (output 0's last).
    Unmarked(usize),
}

/// The marker of `target`: `.NAME.etlcal-pending` beside it.
fn marker_of(target: &Path) -> PathBuf {
    let stem = super::temp_stem(target.file_name().unwrap_or_default());
    target.with_file_name(format!(".{stem}.etlcal-pending"))
}

/// The temporary of `target` of process `pid`.
fn temp_for(target: &Path, pid: u32) -> PathBuf {
    let dir = target.parent().unwrap_or(Path::new("."));
    temp_of(dir, target.file_name().unwrap_or_default(), pid)
}

/// The bytes of a path as a marker keeps it: its OS bytes on Unix (any path); elsewhere
/// its text (module doc of [`super`], "Portability").
fn path_bytes(p: &Path) -> Vec<u8> {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        p.as_os_str().as_bytes().to_vec()
    }
    #[cfg(not(unix))]
    {
        p.to_string_lossy().into_owned().into_bytes()
    }
}

/// The path of bytes [`path_bytes`] gave.
fn path_of(bytes: &[u8]) -> PathBuf {
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        PathBuf::from(std::ffi::OsStr::from_bytes(bytes))
    }
    #[cfg(not(unix))]
    {
        PathBuf::from(String::from_utf8_lossy(bytes).into_owned())
    }
}

/// A marker's content: the writer's pid and the set's outputs (absolute paths, the commit
/// output first), one per line between [`MAGIC`] and [`END`], separated by NUL bytes
/// (a path may hold a newline, never a NUL).
fn marker_bytes(pid: u32, targets: &[PathBuf]) -> Vec<u8> {
    let mut b = format!("{MAGIC}\0{pid}\0").into_bytes();
    for t in targets {
        b.extend_from_slice(&path_bytes(t));
        b.push(0);
    }
    b.extend_from_slice(END.as_bytes());
    b
}

/// A marker read back: `Some((pid, outputs))` when it is whole, `None` when it was cut
/// (or is not a marker).
fn parse_marker(bytes: &[u8]) -> Option<(u32, Vec<PathBuf>)> {
    let mut fields: Vec<&[u8]> = bytes.split(|&b| b == 0).collect();
    if fields.len() < 4 || fields.first() != Some(&MAGIC.as_bytes()) || fields.pop() != Some(END.as_bytes()) {
        return None;
    }
    let pid = std::str::from_utf8(fields[1]).ok()?.parse().ok()?;
    Some((pid, fields[2..].iter().map(|f| path_of(f)).collect()))
}

/// Writes `bytes` to `path` and flushes it to disk.
pub(crate) fn write_synced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = std::fs::File::create(path)?;
    f.write_all(bytes)?;
    f.sync_all()
}

/// Finishes or abandons a file set that a killed run left pending on `path` (see the
/// module doc): after it, `path` holds either the earlier set's file or the new set's,
/// consistently with the set's other outputs. A set whose writer still runs and has not
/// committed is left alone. Costs one `stat` when nothing is pending.
pub(crate) fn complete_pending(path: &Path) -> Result<()> {
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => match path.canonicalize() {
            Ok(t) => t,
            Err(_) => return Ok(()),
        },
        _ => path.to_owned(),
    };
    let marker = marker_of(&target);
    let bytes = match std::fs::read(&marker) {
        Ok(b) => b,
        Err(_) => return Ok(()),
    };
    let Some((pid, targets)) = parse_marker(&bytes) else {
        // Cut while it was written: not a commit, and its process is being killed or gone.
        let _ = std::fs::remove_file(&marker);
        return Ok(());
    };
    let committed = targets
        .first()
        .and_then(|t0| std::fs::read(marker_of(t0)).ok())
        .and_then(|b| parse_marker(&b))
        .is_some_and(|(commit_pid, commit_targets)| commit_pid == pid && commit_targets == targets);
    if committed {
        for t in &targets {
            let tmp = temp_for(t, pid);
            match std::fs::rename(&tmp, t) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(source) => return Err(Error::Io { path: t.clone(), source }),
            }
        }
    } else if process_runs(&pid.to_string()) {
        return Ok(());
    } else {
        for t in &targets {
            let _ = std::fs::remove_file(temp_for(t, pid));
        }
    }
    // The commit's marker last: while it stands, the set can still be completed.
    for t in targets.iter().skip(1).chain(targets.first()) {
        let _ = std::fs::remove_file(marker_of(t));
    }
    Ok(())
}

/// Writes several files as one set, wherever they are: `write` gets one temporary sibling
/// path per output (`.NAME.tmpPID`, in order) and writes each (with the formats' own
/// savers, which validate); then the set is committed and every temporary renamed onto
/// its output, last step. On an error before the commit nothing is replaced and every
/// temporary is removed; a kill at any moment leaves the earlier set or (once the next
/// reader or writer has completed it) the new one: see the module doc. The outputs are
/// checked as [`check_paths`] does (policy of the module doc of [`super`]) first.
pub fn write_file_set<T>(outputs: &[&Path], write: impl FnOnce(&[PathBuf]) -> Result<T>) -> Result<T> {
    write_file_set_observed(outputs, write, &mut |_| {})
}

/// Writes each `(path, bytes)` as one set ([`write_file_set`]): the files of a run whose
/// contents are all known before the first is written (a study's table, summary and
/// plots). Errors: the outputs' checks; an I/O error (nothing replaced).
pub fn write_bytes_set(files: &[(PathBuf, Vec<u8>)]) -> Result<()> {
    let outputs: Vec<&Path> = files.iter().map(|(p, _)| p.as_path()).collect();
    write_file_set(&outputs, |temps| {
        for ((path, bytes), tmp) in files.iter().zip(temps) {
            write_synced(tmp, bytes).map_err(|source| Error::Output { path: path.clone(), source })?;
        }
        Ok(())
    })
}

/// [`write_file_set`], reporting each step of the commit to `step` after it is made.
pub(crate) fn write_file_set_observed<T>(
    outputs: &[&Path],
    write: impl FnOnce(&[PathBuf]) -> Result<T>,
    step: &mut dyn FnMut(Step),
) -> Result<T> {
    let files: Vec<Output<'_>> = outputs.iter().map(|p| Output::File(p)).collect();
    check_paths(&[], &files)?;
    let mut targets = Vec::with_capacity(outputs.len());
    let mut temps = Vec::with_capacity(outputs.len());
    for p in outputs {
        let (target, dir, name) = resolve_output(p)?;
        remove_stale_temps(&dir, &name);
        temps.push(super::temp_sibling(&dir, &name));
        targets.push(absolute(&target));
    }
    let mut committed = false;
    let result = write(&temps).and_then(|value| {
        step(Step::Written);
        commit(outputs, &targets, &temps, &mut committed, step)?;
        Ok(value)
    });
    // A committed set that failed to rename (an I/O error) keeps its temporaries: the next
    // reader or writer completes it (or, failing too, refuses to read a mix).
    if !committed {
        for tmp in &temps {
            let _ = std::fs::remove_file(tmp);
        }
    }
    result
}

/// The commit of a written set: markers (the first output's last), renames, markers
/// removed. An error before the commit's marker is written removes the markers written.
/// `committed` is set once the commit's marker is written.
fn commit(
    outputs: &[&Path],
    targets: &[PathBuf],
    temps: &[PathBuf],
    committed: &mut bool,
    step: &mut dyn FnMut(Step),
) -> Result<()> {
    let io = |k: usize| move |source| Error::Output { path: outputs[k].to_path_buf(), source };
    for (k, (tmp, target)) in temps.iter().zip(targets).enumerate() {
        if let Some(mode) = kept_mode(target) {
            std::fs::set_permissions(tmp, mode).map_err(io(k))?;
        }
    }
    // One output needs no journal: its rename is atomic.
    let journal = targets.len() > 1;
    if journal {
        let bytes = marker_bytes(std::process::id(), targets);
        for k in (1..targets.len()).chain([0]) {
            if let Err(e) = write_synced(&marker_of(&targets[k]), &bytes) {
                for t in targets {
                    let _ = std::fs::remove_file(marker_of(t));
                }
                return Err(io(k)(e));
            }
            *committed = k == 0;
            step(if k == 0 { Step::Committed } else { Step::Marked(k) });
        }
    }
    for (k, (tmp, target)) in temps.iter().zip(targets).enumerate() {
        std::fs::rename(tmp, target).map_err(io(k))?;
        step(Step::Renamed(k));
    }
    if journal {
        for k in (1..targets.len()).chain([0]) {
            std::fs::remove_file(marker_of(&targets[k])).map_err(io(k))?;
            step(Step::Unmarked(k));
        }
    }
    Ok(())
}

// The tests kill a child process with SIGKILL: Unix only.
#[cfg(all(test, unix))]
mod tests;
