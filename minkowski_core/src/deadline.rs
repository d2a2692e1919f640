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
//! any thread (a process runs one plan or operation at a time; batch runs give each task
//! its own process).
//!
//! [`CoreError::TimeLimit`]: crate::error::CoreError::TimeLimit

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::OnceLock;
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

/// Set while the work in progress is cancelled (Ctrl+C: the caller stops waiting for it).
static CANCELLED: AtomicBool = AtomicBool::new(false);

/// Cancel the work in progress: builds stop as at a passed deadline, and a surface
/// extraction skips its remaining queries (its result is to be dropped). Until
/// [`uncancel`].
pub fn cancel() {
    CANCELLED.store(true, Ordering::Relaxed);
}

/// Let work run again after [`cancel`].
pub fn uncancel() {
    CANCELLED.store(false, Ordering::Relaxed);
}

/// Whether the work in progress is cancelled.
#[inline]
pub fn cancelled() -> bool {
    CANCELLED.load(Ordering::Relaxed)
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
}
