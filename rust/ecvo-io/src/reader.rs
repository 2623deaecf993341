//! Streaming frames: a background thread decodes ahead into a bounded channel.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;

use crossbeam_channel::{Receiver, Sender, bounded, unbounded};
use ecvo_core::Camera;

use crate::error::{Error, Result};
use crate::sequence::{Frame, FrameInfo, load_into};

/// Iterator over decoded frames of a sequence, decoded ahead on a background thread.
///
/// At most `prefetch` decoded frames wait in the channel (plus one being decoded), so
/// memory does not grow with the sequence length. Frames handed back with
/// [`FrameReader::recycle`] have their buffers reused. A decode error is yielded once
/// and ends the stream. Dropping the reader early stops and joins the thread.
pub struct FrameReader {
    rx: Option<Receiver<Result<Frame>>>,
    recycle_tx: Option<Sender<Frame>>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    remaining: usize,
    done: bool,
}

impl FrameReader {
    pub(crate) fn spawn(
        camera: Camera,
        root: Option<std::path::PathBuf>,
        frames: Arc<[FrameInfo]>,
        count: usize,
        prefetch: usize,
    ) -> FrameReader {
        let (tx, rx) = bounded::<Result<Frame>>(prefetch.max(1));
        let (recycle_tx, recycle_rx) = unbounded::<Frame>();
        let stop = Arc::new(AtomicBool::new(false));
        let stop_thread = stop.clone();
        let body = move || {
            for index in 0..count {
                if stop_thread.load(Ordering::Relaxed) {
                    return;
                }
                let mut frame = recycle_rx.try_recv().unwrap_or_default();
                let result = load_into(&camera, root.as_deref(), &frames[index], index, &mut frame)
                    .map(|()| frame);
                let failed = result.is_err();
                if tx.send(result).is_err() || failed {
                    return;
                }
            }
        };
        let handle = std::thread::Builder::new()
            .name("ecvo-frame-reader".into())
            .spawn(body);
        match handle {
            Ok(handle) => FrameReader {
                rx: Some(rx),
                recycle_tx: Some(recycle_tx),
                stop,
                handle: Some(handle),
                remaining: count,
                done: false,
            },
            Err(e) => {
                // No thread: yield the spawn failure as the only item.
                let (tx, rx) = bounded(1);
                let _ = tx.send(Err(Error::Io {
                    path: "<frame reader thread>".into(),
                    source: e,
                }));
                FrameReader {
                    rx: Some(rx),
                    recycle_tx: None,
                    stop,
                    handle: None,
                    remaining: count,
                    done: false,
                }
            }
        }
    }

    /// Hands a frame back so that its buffers are reused for a later frame.
    pub fn recycle(&self, frame: Frame) {
        if let Some(tx) = &self.recycle_tx {
            // Fails only once the reader thread has finished; the frame is then dropped.
            let _ = tx.send(frame);
        }
    }

    /// Number of frames not yet yielded (an upper bound if the stream ends in error).
    pub fn remaining(&self) -> usize {
        self.remaining
    }

    fn shutdown(&mut self) -> bool {
        self.stop.store(true, Ordering::Relaxed);
        // Dropping the receiver makes a blocked `send` in the thread fail at once.
        self.rx = None;
        self.recycle_tx = None;
        match self.handle.take() {
            Some(h) => h.join().is_ok(),
            None => true,
        }
    }
}

impl Iterator for FrameReader {
    type Item = Result<Frame>;

    fn next(&mut self) -> Option<Result<Frame>> {
        if self.done {
            return None;
        }
        let received = self.rx.as_ref().and_then(|rx| rx.recv().ok());
        match received {
            Some(Ok(frame)) => {
                self.remaining = self.remaining.saturating_sub(1);
                Some(Ok(frame))
            }
            Some(Err(e)) => {
                self.done = true;
                self.shutdown();
                Some(Err(e))
            }
            None => {
                self.done = true;
                let clean = self.shutdown();
                if !clean || self.remaining > 0 {
                    // The thread ended without sending every frame or an error.
                    self.remaining = 0;
                    return Some(Err(Error::ReaderPanicked));
                }
                None
            }
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        if self.done {
            (0, Some(0))
        } else {
            (0, Some(self.remaining + 1))
        }
    }
}

impl Drop for FrameReader {
    fn drop(&mut self) {
        self.shutdown();
    }
}
