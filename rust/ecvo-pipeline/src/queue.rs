//! The bounded FIFO queue between two stages.
//!
//! A `VecDeque` with its capacity reserved up front under a `Mutex`, with two
//! condition variables: neither pushing nor popping allocates. It can block the
//! producer (offline admission) or evict the oldest waiting item (live admission),
//! and it records the depth it reaches for the statistics.

use std::collections::VecDeque;
use std::sync::{Condvar, Mutex, MutexGuard};

use crate::stats::QueueStats;

struct Inner<T> {
    items: VecDeque<T>,
    closed: bool,
    pushes: u64,
    depth_sum: u64,
    max_depth: usize,
}

/// A bounded multi-producer, multi-consumer FIFO queue.
pub(crate) struct Queue<T> {
    inner: Mutex<Inner<T>>,
    not_empty: Condvar,
    not_full: Condvar,
    capacity: usize,
}

/// Locks a mutex, ignoring poisoning: every critical section in this crate leaves its
/// data consistent, and a panicking stage is reported through the pipeline's error.
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl<T> Queue<T> {
    /// An empty open queue holding at most `capacity` (at least 1) items.
    pub(crate) fn new(capacity: usize) -> Self {
        let capacity = capacity.max(1);
        Queue {
            inner: Mutex::new(Inner {
                items: VecDeque::with_capacity(capacity),
                closed: false,
                pushes: 0,
                depth_sum: 0,
                max_depth: 0,
            }),
            not_empty: Condvar::new(),
            not_full: Condvar::new(),
            capacity,
        }
    }

    fn record(inner: &mut Inner<T>) {
        let depth = inner.items.len();
        inner.pushes += 1;
        inner.depth_sum += depth as u64;
        inner.max_depth = inner.max_depth.max(depth);
    }

    /// Appends `item`, waiting while the queue is full. Gives the item back if the
    /// queue is (or becomes) closed.
    pub(crate) fn push_blocking(&self, item: T) -> Result<(), T> {
        let mut g = lock(&self.inner);
        while !g.closed && g.items.len() >= self.capacity {
            g = self.not_full.wait(g).unwrap_or_else(|e| e.into_inner());
        }
        if g.closed {
            return Err(item);
        }
        g.items.push_back(item);
        Self::record(&mut g);
        drop(g);
        self.not_empty.notify_one();
        Ok(())
    }

    /// Appends `item` without waiting; when the queue is full the oldest item is
    /// removed to make room and returned. Gives the item back if the queue is closed.
    pub(crate) fn push_evicting(&self, item: T) -> Result<Option<T>, T> {
        let mut g = lock(&self.inner);
        if g.closed {
            return Err(item);
        }
        let evicted = if g.items.len() >= self.capacity {
            g.items.pop_front()
        } else {
            None
        };
        g.items.push_back(item);
        Self::record(&mut g);
        drop(g);
        self.not_empty.notify_one();
        Ok(evicted)
    }

    /// Appends `item` if there is room, else gives it back (also when closed).
    pub(crate) fn try_push(&self, item: T) -> Result<(), T> {
        let mut g = lock(&self.inner);
        if g.closed || g.items.len() >= self.capacity {
            return Err(item);
        }
        g.items.push_back(item);
        Self::record(&mut g);
        drop(g);
        self.not_empty.notify_one();
        Ok(())
    }

    /// The most items it holds.
    pub(crate) fn capacity(&self) -> usize {
        self.capacity
    }

    /// Items waiting now.
    pub(crate) fn len(&self) -> usize {
        lock(&self.inner).items.len()
    }

    /// Removes the oldest item without waiting.
    pub(crate) fn try_pop(&self) -> Option<T> {
        let item = lock(&self.inner).items.pop_front();
        if item.is_some() {
            self.not_full.notify_one();
        }
        item
    }

    /// Removes the oldest item, waiting for one; `None` once the queue is closed and
    /// empty.
    pub(crate) fn pop(&self) -> Option<T> {
        let mut g = lock(&self.inner);
        loop {
            if let Some(item) = g.items.pop_front() {
                drop(g);
                self.not_full.notify_one();
                return Some(item);
            }
            if g.closed {
                return None;
            }
            g = self.not_empty.wait(g).unwrap_or_else(|e| e.into_inner());
        }
    }

    /// Refuses further pushes and wakes every waiter; items already queued can still
    /// be popped.
    pub(crate) fn close(&self) {
        lock(&self.inner).closed = true;
        self.not_empty.notify_all();
        self.not_full.notify_all();
    }

    /// Depth statistics so far.
    pub(crate) fn stats(&self) -> QueueStats {
        let g = lock(&self.inner);
        QueueStats {
            capacity: self.capacity,
            depth: g.items.len(),
            max_depth: g.max_depth,
            mean_depth: if g.pushes == 0 {
                0.0
            } else {
                g.depth_sum as f64 / g.pushes as f64
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifo_eviction_and_close() {
        let q = Queue::new(2);
        assert_eq!(q.push_evicting(1), Ok(None));
        assert_eq!(q.push_evicting(2), Ok(None));
        assert_eq!(q.push_evicting(3), Ok(Some(1)));
        assert_eq!(q.try_push(4), Err(4));
        assert_eq!(q.pop(), Some(2));
        q.close();
        assert_eq!(q.push_blocking(5), Err(5));
        assert_eq!(q.pop(), Some(3));
        assert_eq!(q.pop(), None);
        let s = q.stats();
        assert_eq!((s.capacity, s.max_depth, s.depth), (2, 2, 0));
        assert!((s.mean_depth - 5.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn blocked_producer_wakes_on_close() {
        let q = std::sync::Arc::new(Queue::new(1));
        q.push_blocking(1).unwrap();
        let q2 = q.clone();
        let t = std::thread::spawn(move || q2.push_blocking(2));
        std::thread::sleep(std::time::Duration::from_millis(20));
        q.close();
        assert_eq!(t.join().unwrap(), Err(2));
    }
}
