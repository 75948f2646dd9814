//! [`Progress`]: how long work (rendering a rig, detecting a dataset, Monte Carlo trials, a
//! temperature procedure) tells whoever drives it how far it has come, without the
//! libraries knowing how that is shown (a terminal bar in the CLI, nothing in tests and
//! Python).

/// A receiver of progress reports. Work calls [`Progress::start`] once, then
/// [`Progress::advance`] from any thread as steps finish, then [`Progress::finish`].
///
/// ```
/// use core::sync::atomic::{AtomicUsize, Ordering};
/// use etl_core::progress::Progress;
/// struct Count(AtomicUsize);
/// impl Progress for Count {
///     fn advance(&self, steps: usize) {
///         self.0.fetch_add(steps, Ordering::Relaxed);
///     }
/// }
/// let c = Count(AtomicUsize::new(0));
/// c.start(3, "trials");
/// (0..3).for_each(|_| c.advance(1));
/// c.finish();
/// assert_eq!(c.0.load(Ordering::Relaxed), 3);
/// ```
pub trait Progress: Sync + Send {
    /// Work of `len` steps, named `label` (e.g. "rendering"), begins.
    fn start(&self, _len: usize, _label: &str) {}
    /// `steps` more steps are done.
    fn advance(&self, _steps: usize) {}
    /// The work is done (or abandoned).
    fn finish(&self) {}
}

/// Reports nowhere.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {}
