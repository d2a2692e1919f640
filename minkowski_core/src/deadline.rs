//! A process-wide time limit on the long native work of a C-space: octree builds and
//! refinements stop when it passes and report [`CoreError::TimeLimit`], changing nothing.
//!
//! The caller (the planner) sets it before a step that must end by its time limit and
//! clears it after ([`set_deadline`]); one value per process, like the memory budget of
//! the candidate records: it bounds every build in the process while it is set, so one
//! plan at a time may set it (the planner's own use; batch runs give each task its own
//! process).
//!
//! Cancelling ([`cancel`]: the Python binding does when Ctrl+C arrives) makes the deadline
//! pass at once and the surface extraction skip its queries, until [`uncancel`]. Like the
//! deadline it is one flag for the process: it stops every native call running then, on
//! any thread. A call that ran while some cancel was in force may hold half a result, so
//! each call takes a [`CancelWatch`] when it starts and asks it when it ends whether a
//! cancel touched it ([`CancelWatch::touched`]): the binding then raises instead of
//! returning what it made.
//!
//! [`CoreError::TimeLimit`]: crate::error::CoreError::TimeLimit

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// No deadline.
const NONE: u64 = u64::MAX;

/// Nanoseconds after [`epoch`] at which the work stops ([`NONE`]: never).
static DEADLINE_NS: AtomicU64 = AtomicU64::new(NONE);

/// The instant the deadlines are counted from (the first use).
fn epoch() -> Instant {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    *EPOCH.get_or_init(Instant::now)
}

fn now_ns() -> u64 {
    u64::try_from(epoch().elapsed().as_nanos()).unwrap_or(NONE - 1)
}

/// Stop the work `after` from now (`None`: never); a zero `after` stops it at once.
pub fn set_deadline(after: Option<Duration>) {
    DEADLINE_NS.store(deadline_at(now_ns(), after), Ordering::Relaxed);
}

/// Whether the deadline has passed, or the work was cancelled ([`cancel`]).
#[inline]
pub fn passed() -> bool {
    cancelled() || is_past(DEADLINE_NS.load(Ordering::Relaxed), now_ns())
}

/// The process's cancels.
static CANCELS: Cancels = Cancels::new();

/// Cancel the work in progress: builds stop as at a passed deadline, and a surface
/// extraction skips its remaining queries (its result is to be dropped). Until the
/// matching [`uncancel`].
pub fn cancel() {
    CANCELS.cancel();
}

/// End one [`cancel`]: work runs again once every cancel has ended.
pub fn uncancel() {
    CANCELS.uncancel();
}

/// Whether the work in progress is cancelled.
#[inline]
pub fn cancelled() -> bool {
    CANCELS.in_force()
}

/// What a call saw of the process's cancels when it started.
pub fn watch_cancels() -> CancelWatch {
    CANCELS.watch()
}

/// Cancels made and in force.
#[derive(Debug)]
struct Cancels {
    /// How many cancels were ever made, and how many are in force; changed together.
    log: Mutex<(u64, u32)>,
    /// The second of `log`, for the work's cheap checks.
    in_force: AtomicU32,
}

/// What a call saw of the cancels when it started ([`watch_cancels`]): ask
/// [`CancelWatch::touched`] when it ends.
#[derive(Clone, Copy, Debug)]
pub struct CancelWatch {
    cancels: &'static Cancels,
    made: u64,
    in_force: u32,
}

impl CancelWatch {
    /// Whether a cancel was in force at some time since the watch began (one in force
    /// then, or one made since): the work may have stopped half-way.
    pub fn touched(&self) -> bool {
        self.in_force > 0 || self.cancels.log().0 != self.made
    }
}

impl Cancels {
    const fn new() -> Self {
        Cancels { log: Mutex::new((0, 0)), in_force: AtomicU32::new(0) }
    }

    fn log(&self) -> std::sync::MutexGuard<'_, (u64, u32)> {
        self.log.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn cancel(&self) {
        let mut log = self.log();
        log.0 += 1;
        log.1 += 1;
        self.in_force.store(log.1, Ordering::Relaxed);
    }

    fn uncancel(&self) {
        let mut log = self.log();
        log.1 = log.1.saturating_sub(1);
        self.in_force.store(log.1, Ordering::Relaxed);
    }

    fn in_force(&self) -> bool {
        self.in_force.load(Ordering::Relaxed) > 0
    }

    fn watch(&'static self) -> CancelWatch {
        let log = self.log();
        CancelWatch { cancels: self, made: log.0, in_force: log.1 }
    }
}

/// The deadline `after` from `now` (nanoseconds after [`epoch`]; [`NONE`] for none).
fn deadline_at(now: u64, after: Option<Duration>) -> u64 {
    after.map_or(NONE, |d| now.saturating_add(u64::try_from(d.as_nanos()).unwrap_or(NONE)).min(NONE - 1))
}

/// Whether the deadline `at` has passed at `now`.
fn is_past(at: u64, now: u64) -> bool {
    at != NONE && now >= at
}

#[cfg(test)]
mod tests {
    use super::*;

    // the process-wide value is not set here: tests of builds run beside these

    #[test]
    fn a_deadline_passes_at_its_time_and_none_never() {
        let at = deadline_at(1_000, Some(Duration::from_nanos(500)));
        assert_eq!(at, 1_500);
        assert!(!is_past(at, 1_499) && is_past(at, 1_500) && is_past(at, u64::MAX - 1));
        assert!(is_past(deadline_at(1_000, Some(Duration::ZERO)), 1_000));
        assert!(!is_past(deadline_at(1_000, None), u64::MAX - 1));
    }

    #[test]
    fn a_deadline_far_away_does_not_wrap_around() {
        let at = deadline_at(u64::MAX - 10, Some(Duration::from_secs(u64::MAX)));
        assert_eq!(at, NONE - 1);
        assert!(!is_past(at, u64::MAX - 10));
    }

    #[test]
    fn a_watch_sees_a_cancel_made_or_in_force_during_its_call() {
        static OWN: Cancels = Cancels::new(); // not the process's: builds run beside this
        let before = OWN.watch();
        assert!(!before.touched());
        OWN.cancel();
        let during = OWN.watch();
        assert!(OWN.in_force() && before.touched() && during.touched());
        OWN.cancel();
        OWN.uncancel();
        assert!(OWN.in_force(), "one cancel is still in force");
        OWN.uncancel();
        assert!(!OWN.in_force() && during.touched());
        assert!(!OWN.watch().touched());
    }
}
