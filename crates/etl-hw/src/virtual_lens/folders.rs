//! The virtual lens's folders, `TMPDIR/etl-vlens-PID-N`, each holding the `lens` symlink
//! to a pty: named by the owning process, so that a process that died without dropping its
//! lens (SIGKILL, an abort) leaves a folder the next lens of any process can remove.
//!
//! Three ways out, for the three ways a process ends:
//! - a dropped [`super::VirtualLens`] removes its own folder;
//! - a signal the process handles ([`remove_live`], from a signal-waiting thread) removes
//!   every folder the process still holds;
//! - a process killed outright is swept by the next [`super::VirtualLens::spawn`]
//!   ([`sweep_dead`]), on any process.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

const PREFIX: &str = "etl-vlens-";

/// The entries a lens's folder may hold: a folder with anything else is not removed.
const ENTRIES: [&str; 2] = ["lens", "lens.new"];

static SERIAL: AtomicU64 = AtomicU64::new(0);

/// The folders this process's lenses hold now.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|p| p.into_inner())
}

/// A new folder's path for this process (not created).
pub(super) fn next_path() -> PathBuf {
    let n = SERIAL.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("{PREFIX}{}-{n}", std::process::id()))
}

/// Records `dir` as held by this process.
pub(super) fn hold(dir: &Path) {
    live().push(dir.to_owned());
}

/// Removes `dir` (its lens entries, then the folder) and forgets it.
pub(super) fn release(dir: &Path) {
    remove(dir);
    live().retain(|d| d != dir);
}

/// Removes every folder this process's lenses still hold: for a signal handler's thread
/// just before the process exits, when no destructor will run. The lenses' ports stop
/// resolving; nothing else changes.
pub fn remove_live() {
    for dir in live().drain(..) {
        remove(&dir);
    }
}

/// Removes the folders of processes that no longer run, in `tmp` (the system's temporary
/// folder in use). A folder whose process runs, whose name does not parse, or that holds
/// anything but a lens's entries is left alone. Returns how many were removed.
pub fn sweep_dead(tmp: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(tmp) else { return 0 };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(owner_pid) else { continue };
        if pid == std::process::id() || process_runs(pid) {
            continue;
        }
        let dir = entry.path();
        if only_lens_entries(&dir) && remove(&dir) {
            removed += 1;
        }
    }
    removed
}

/// The PID in a folder name `etl-vlens-PID-N`.
fn owner_pid(name: &str) -> Option<u32> {
    let (pid, n) = name.strip_prefix(PREFIX)?.split_once('-')?;
    n.parse::<u64>().ok()?;
    pid.parse().ok()
}

/// Whether a process `pid` exists (signal 0: EPERM means it runs under another user).
fn process_runs(pid: u32) -> bool {
    let Ok(pid) = i32::try_from(pid) else { return true };
    !matches!(nix::sys::signal::kill(nix::unistd::Pid::from_raw(pid), None), Err(nix::errno::Errno::ESRCH))
}

fn only_lens_entries(dir: &Path) -> bool {
    let Ok(meta) = std::fs::symlink_metadata(dir) else { return false };
    if !meta.is_dir() {
        return false;
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return false };
    entries.flatten().all(|e| ENTRIES.iter().any(|n| e.file_name() == *n))
}

/// Removes a lens folder; true when it is gone.
fn remove(dir: &Path) -> bool {
    for n in ENTRIES {
        let _ = std::fs::remove_file(dir.join(n));
    }
    std::fs::remove_dir(dir).is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dead_processs_folder_is_swept_and_a_live_or_foreign_one_kept() {
        let tmp = tempfile::tempdir().unwrap();
        // A PID above the kernel's largest (2^22) runs nowhere.
        let dead = tmp.path().join(format!("{PREFIX}4999999-0"));
        std::fs::create_dir(&dead).unwrap();
        std::os::unix::fs::symlink("/dev/null", dead.join("lens")).unwrap();
        let running = tmp.path().join(format!("{PREFIX}1-3"));
        std::fs::create_dir(&running).unwrap();
        let foreign = tmp.path().join(format!("{PREFIX}4999998-0"));
        std::fs::create_dir(&foreign).unwrap();
        std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
        let unparsed = tmp.path().join(format!("{PREFIX}x-0"));
        std::fs::create_dir(&unparsed).unwrap();
        assert_eq!(sweep_dead(tmp.path()), 1);
        assert!(!dead.exists());
        assert!(running.exists() && foreign.join("notes.txt").exists() && unparsed.exists());
    }

    #[test]
    fn folder_names_parse_to_their_owner() {
        assert_eq!(owner_pid("etl-vlens-123-4"), Some(123));
        assert_eq!(owner_pid("etl-vlens-123"), None);
        assert_eq!(owner_pid("etl-vlens-123-x"), None);
        assert_eq!(owner_pid("other-123-4"), None);
    }
}
