//! Ctrl-C, SIGTERM and SIGHUP for the verbs that hold a virtual lens (`lens-sim`,
//! `lens --virtual`, `thermal calibrate --virtual`): the lens's folder in the temporary
//! directory is removed before the process dies of the signal, as it would have without
//! the handler (same signal, same exit status), so that a stopped simulator leaves nothing.
//!
//! The signals are blocked in the calling thread, and so in every thread it starts after,
//! and one thread waits for them (`sigwait`): no code runs in a signal handler, so the
//! removal may lock and allocate.

use etl_formats::{Error, Result};
use nix::sys::signal::{pthread_sigmask, raise, signal, SigHandler, SigSet, SigmaskHow, Signal};

/// Call first in the verb, before it starts any thread (the mask is inherited).
pub fn remove_lens_folders_on_signal() -> Result<()> {
    let mut set = SigSet::empty();
    for s in [Signal::SIGINT, Signal::SIGTERM, Signal::SIGHUP] {
        set.add(s);
    }
    pthread_sigmask(SigmaskHow::SIG_BLOCK, Some(&set), None)
        .map_err(|e| Error::invalid("signals", format!("cannot block the stop signals: {e}")))?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            let Ok(sig) = set.wait() else { return };
            etl_hw::virtual_lens::folders::remove_live();
            die_of(sig, &set);
        })
        .map_err(|e| Error::invalid("signals", format!("cannot start the signal thread: {e}")))?;
    Ok(())
}

/// Ends the process by `sig` with its default action, as if no handler had been installed.
fn die_of(sig: Signal, set: &SigSet) -> ! {
    // SAFETY: SIG_DFL installs no Rust code as a handler.
    let _ = unsafe { signal(sig, SigHandler::SigDfl) };
    let _ = pthread_sigmask(SigmaskHow::SIG_UNBLOCK, Some(set), None);
    let _ = raise(sig);
    std::process::exit(128 + sig as i32)
}
