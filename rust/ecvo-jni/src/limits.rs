//! How many trackers a process may hold at once.
//!
//! Each tracker owns its pipeline: three stage threads (filter, tracker, geometry)
//! and a compute pool of `threads` workers, and the memory of its size
//! (`nativeMemoryNeeded`). Threads are not shared between trackers, so their number
//! is capped instead: [`MAX_LIVE_TRACKERS`] trackers, about 80 threads with the
//! default 2 workers; `nativeInit` beyond it is an `IllegalStateException` saying so.
//! A tracker's slot is given back when its native side is dropped: at `close()`, or,
//! for a `Tracker` dropped without `close()`, when the garbage collector's Cleaner
//! releases it (a call still running on another thread holds it until it returns).

use std::sync::atomic::{AtomicUsize, Ordering};

use crate::error::Failure;

/// The most trackers a process may hold at once.
pub const MAX_LIVE_TRACKERS: usize = 16;

static LIVE: AtomicUsize = AtomicUsize::new(0);

/// One tracker's place under [`MAX_LIVE_TRACKERS`], given back on drop.
#[derive(Debug)]
pub struct Slot(());

impl Drop for Slot {
    fn drop(&mut self) {
        LIVE.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Takes a slot, or refuses when [`MAX_LIVE_TRACKERS`] are live.
pub fn reserve() -> Result<Slot, Failure> {
    let taken = LIVE.fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
        (n < MAX_LIVE_TRACKERS).then_some(n + 1)
    });
    match taken {
        Ok(_) => Ok(Slot(())),
        Err(n) => Err(Failure::IllegalState(format!(
            "{n} trackers are live, the most a process may hold (each has its own threads and memory): close() one first; a Tracker dropped without close() keeps its place until the garbage collector releases it"
        ))),
    }
}

/// Trackers live now.
#[cfg(test)]
fn live() -> usize {
    LIVE.load(Ordering::Acquire)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_are_capped_and_given_back() {
        let base = live();
        let slots: Vec<Slot> = (base..MAX_LIVE_TRACKERS)
            .map(|_| reserve().expect("a free slot"))
            .collect();
        assert_eq!(live(), MAX_LIVE_TRACKERS);
        match reserve() {
            Err(Failure::IllegalState(m)) => {
                assert!(
                    m.contains("16 trackers are live") && m.contains("close()"),
                    "{m}"
                )
            }
            other => panic!("{other:?}"),
        }
        drop(slots);
        assert_eq!(live(), base);
        assert!(reserve().is_ok());
    }
}
