//! The worker threads of etlcal's parallel parts (rayon), one pool per process.
//!
//! After `os.fork()` the child holds none of its parent's threads, but rayon's global
//! pool, inherited in memory, believes its workers still run: the child's first parallel
//! call would wait for them for ever (a render, a detection, a study). So every call whose
//! work has parallel parts runs it through [`detach`], in a pool of this process: a pool
//! built by another process (the parent, before a fork) is abandoned, not used, and a new
//! one is built. Everything else about the pool is rayon's default (one thread per core,
//! or `RAYON_NUM_THREADS`). Work with no parallel parts (the lens's serial I/O, in
//! lens.rs) stays on `py.detach`: `install` would move it to a worker thread for nothing.

use std::sync::{Arc, Mutex};

use pyo3::prelude::*;

/// The pool and the PID of the process that built it.
static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);

/// This process's pool, built on first use and again after a fork; `None` when the OS
/// refuses threads (the work then runs on rayon's global pool, as before).
fn pool() -> Option<Arc<rayon::ThreadPool>> {
    let pid = std::process::id();
    let mut slot = POOL.lock().unwrap_or_else(|p| p.into_inner());
    if let Some((owner, p)) = slot.as_ref() {
        if *owner == pid {
            return Some(Arc::clone(p));
        }
    }
    // The parent's pool: its threads do not exist here, and dropping it would signal
    // them; it is left as memory.
    if let Some(stale) = slot.take() {
        std::mem::forget(stale);
    }
    let p = Arc::new(rayon::ThreadPoolBuilder::new().thread_name(|i| format!("etlcal-{i}")).build().ok()?);
    *slot = Some((pid, Arc::clone(&p)));
    Some(p)
}

/// Builds this process's pool now (at import): its threads start while the interpreter
/// loads the rest, so that the first parallel call does not pay for them (0.5 ms of a
/// 1.5 ms detection). A process forked later builds its own on first use, as before.
pub fn prepare() {
    let _ = pool();
}

/// `py.detach(f)` with `f`'s parallel parts on this process's pool.
pub fn detach<T: Send, F: FnOnce() -> T + Send>(py: Python<'_>, f: F) -> T {
    let pool = pool();
    py.detach(move || match pool {
        Some(p) => p.install(f),
        None => f(),
    })
}
