//! A process-wide time limit on the long native work of a C-space: octree builds and
//! refinements stop when it passes and report [`CoreError::TimeLimit`], changing nothing.
//!
//! The caller (the planner) sets it before a step that must end by its time limit and
//! clears it after ([`set_deadline`]); one value per process, like the memory budget of
//! the candidate records, since the work it bounds runs one C-space at a time.
//!
//! [`CoreError::TimeLimit`]: crate::error::CoreError::TimeLimit

use std::sync::atomic::{AtomicU64, Ordering};
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

/// Stop the work `after` from now (`None`: never); a negative or zero `after` stops it at
/// once.
pub fn set_deadline(after: Option<Duration>) {
    let at = after.map_or(NONE, |d| now_ns().saturating_add(u64::try_from(d.as_nanos()).unwrap_or(NONE)).min(NONE - 1));
    DEADLINE_NS.store(at, Ordering::Relaxed);
}

/// Whether the deadline has passed.
#[inline]
pub fn passed() -> bool {
    let at = DEADLINE_NS.load(Ordering::Relaxed);
    at != NONE && now_ns() >= at
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_deadline_passes_after_its_time_and_none_never() {
        set_deadline(Some(Duration::from_millis(30)));
        assert!(!passed());
        std::thread::sleep(Duration::from_millis(40));
        assert!(passed());
        set_deadline(None);
        assert!(!passed());
        set_deadline(Some(Duration::ZERO));
        assert!(passed());
        set_deadline(None);
    }
}
