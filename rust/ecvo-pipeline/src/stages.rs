//! The three stage threads: filter, tracker and geometry (section 4.1, Figure 4).

use super::*;
use crate::stats::thread_cpu;

/// The filter stage: prepares each frame. While the tracker is behind (its queue is
/// not empty), it also computes the frame's \[A\] against the frame it prepared just
/// before, which is the tracker's previous frame unless that one is lost: the
/// tracker then only corrects against its references, and the two stages share the
/// work more evenly. \[A\] depends on the two frames alone, so the poses are the same.
pub(crate) fn filter_stage(
    s: &Shared,
    mut preparer: Preparer,
    config: &Config,
    compute: &rayon::ThreadPool,
) {
    let mut estimator =
        MotionEstimator::with_capacity(ecvo_core::prepare::max_template_points(config));
    // The tracker's `MOTION` settings, with the depth-noise model it last published.
    let mut motion = working_motion(&config.motion);
    // The frame prepared last, while the next one may still follow at once.
    let mut last: Option<PooledFrame> = None;
    // What the tracker's prediction for the next frame will be, as far as this stage
    // knows it: the [A] it computed ahead for the frame `last` (or that frame being
    // the first, with nothing to predict from).
    let mut chain = Chain::default();
    loop {
        let raw = match s.input.try_pop() {
            Some(raw) => raw,
            None => {
                // Nothing waiting: let the last frame go (only the tracker keeps frames
                // while the pipeline is idle), then wait.
                last = None;
                match s.input.pop() {
                    Some(raw) => raw,
                    None => break,
                }
            }
        };
        if s.aborted() {
            break;
        }
        let Some(mut slot) = s.frames.acquire(&s.abort) else {
            break;
        };
        s.hook(Stage::Filter, raw.sequence);
        let slot_mut = Arc::get_mut(&mut slot).expect("an acquired slot is exclusive");
        let view = FrameView {
            timestamp: raw.timestamp,
            intensity: &raw.intensity,
            depth: &raw.depth,
        };
        let prepared = &mut slot_mut.frame;
        // Timed inside the pool: a stage's time is its work, not its wait for a thread.
        let (result, ahead, filtered_in, filtered_cpu) = compute.install(|| {
            let (t0, c0) = (Instant::now(), thread_cpu());
            // New intrinsics (`Pipeline::set_intrinsics`), checked when they were set.
            let r = if *preparer.camera() == raw.camera {
                Ok(())
            } else {
                preparer.set_intrinsics(raw.camera)
            }
            .and_then(|()| preparer.prepare_turned_into(view, raw.depth_time, prepared));
            // The tracker is behind when its queue is full: this frame would wait.
            let behind = s.prepared.len() >= s.prepared.capacity();
            let ahead = match (&r, &last) {
                (Ok(()), Some(prev)) => {
                    let published = *lock(&s.velocity);
                    let offline = s.admission == Admission::Offline;
                    // With an IMU the prior depends on the tracker's bias estimate.
                    let imu = lock(&s.imu).ring.pushed() > 0;
                    let known = (!imu)
                        .then(|| {
                            chain.prior(
                                config,
                                prev,
                                prepared.timestamp,
                                behind,
                                offline,
                                published,
                            )
                        })
                        .flatten();
                    known.map(|prior| {
                        let (t1, c1) = (Instant::now(), thread_cpu());
                        motion.depth_noise = *lock(&s.depth_noise);
                        let result =
                            frame_to_frame(&mut estimator, prepared, prev, prior.as_ref(), &motion);
                        Ahead {
                            against: prev.sequence(),
                            prior,
                            depth_noise: motion.depth_noise,
                            result,
                            took: t1.elapsed(),
                            took_cpu: thread_cpu().saturating_sub(c1),
                        }
                    })
                }
                _ => None,
            };
            if r.is_ok() {
                chain.prepared(raw.sequence, prepared.timestamp, ahead.as_ref());
            }
            (r, ahead, t0.elapsed(), thread_cpu().saturating_sub(c0))
        });
        let filtered_in = filtered_in.saturating_sub(ahead.map_or(Duration::ZERO, |a| a.took));
        let filtered_cpu =
            filtered_cpu.saturating_sub(ahead.map_or(Duration::ZERO, |a| a.took_cpu));
        slot_mut.meta = FrameMeta {
            sequence: raw.sequence,
            pushed_at: raw.pushed_at,
            ahead,
            filtered_in,
            filtered_cpu,
            imu_upto: raw.imu_upto,
        };
        // [A] computed ahead is the tracker's work: the filter's figure leaves it out and
        // the tracker stage books it with the frame, used or discarded.
        lock(&s.timers.filter).record(filtered_in);
        s.give_raw(raw);
        if let Err(e) = result {
            log::warn!("ecvo-pipeline: frame not prepared: {e}");
            s.frames.give_back(slot);
            s.update_progress(|p| p.failed_preparations += 1);
            continue;
        }
        if ahead.is_some() {
            s.update_progress(|p| p.ahead_computed += 1);
        }
        let frame = s.frames.share(slot);
        last = Some(frame.clone());
        match s.admission {
            Admission::Offline => {
                if s.prepared.push_blocking(frame).is_err() {
                    break;
                }
            }
            Admission::Live => match s.prepared.push_evicting(frame) {
                Ok(None) => {}
                Ok(Some(old)) => {
                    drop(old);
                    s.update_progress(|p| p.dropped_at_tracker += 1);
                }
                Err(_) => break,
            },
        }
    }
}

pub(crate) fn tracker_stage(
    s: &Shared,
    mut tracker: Tracker<PooledFrame>,
    compute: &rayon::ThreadPool,
    outputs: Option<Sender<TrackedFrame>>,
) {
    let all_levels = s.levels.min(u8::MAX as usize) as u8;
    // IMU samples handed to the tracker so far.
    let mut imu_fed = 0u64;
    while let Some(frame) = s.prepared.pop() {
        if s.aborted() {
            break;
        }
        let meta = frame.meta();
        s.hook(Stage::Tracker, meta.sequence);
        let for_geometry = s.geometry.is_some().then(|| frame.clone());
        let mut used_ahead = false;
        crate::imu::feed(s, &mut tracker, &mut imu_fed, meta.imu_upto);
        let (out, tracked_in, tracked_cpu) = compute.install(|| {
            let (t0, c0) = (Instant::now(), thread_cpu());
            let out = tracker.track_with(frame, |prev, prior, noise| {
                let a = meta.ahead.filter(|a| {
                    a.against == prev.sequence()
                        && a.prior.as_ref() == prior
                        && a.depth_noise == noise
                })?;
                used_ahead = true;
                Some(a.result)
            });
            (out, t0.elapsed(), thread_cpu().saturating_sub(c0))
        });
        // The [A] the filter stage computed ahead for this frame is tracker work.
        let tracked_in = tracked_in + meta.ahead.map_or(Duration::ZERO, |a| a.took);
        let tracked_cpu = tracked_cpu + meta.ahead.map_or(Duration::ZERO, |a| a.took_cpu);
        if used_ahead {
            s.update_progress(|p| p.ahead_used += 1);
        }
        *lock(&s.depth_noise) = tracker.depth_noise();
        *lock(&s.velocity) = Some((
            meta.sequence,
            tracker
                .velocity()
                .filter(|v| v.index == out.index)
                .map(|v| (v.motion, v.dt)),
        ));

        let anchored = out.index == 0 || out.reanchored;
        let reference_levels = if anchored {
            all_levels
        } else {
            out.reference_levels
        };
        let is_reference = anchored || out.reference_levels > 0;
        if let Some(frame) = for_geometry
            && is_reference
        {
            let item = GeometryItem {
                frame,
                pose: out.pose,
            };
            match s.admission {
                Admission::Offline => {
                    s.update_progress(|p| p.geometry_sent += 1);
                    if s.to_geometry.push_blocking(item).is_err() {
                        s.update_progress(|p| p.geometry_sent -= 1);
                    }
                }
                Admission::Live => {
                    s.update_progress(|p| p.geometry_sent += 1);
                    if s.to_geometry.try_push(item).is_err() {
                        s.update_progress(|p| {
                            p.geometry_sent -= 1;
                            p.geometry_skipped += 1;
                        });
                    }
                }
            }
        }

        let now = Instant::now();
        *lock(&s.latest) = LatestPose {
            tracked: out.index + 1,
            sequence: meta.sequence,
            timestamp: out.timestamp,
            pose: out.pose,
            state: out.state,
            reference_levels,
            registration: out.registration,
            lost_reason: out.lost_reason,
            pushed_at: meta.pushed_at,
            tracked_at: now,
        };
        copy_counters(&mut lock(&s.counters), tracker.counters());
        if s.keep_trajectory {
            let record = PoseRecord {
                sequence: meta.sequence,
                index: out.index,
                timestamp: out.timestamp,
                pose: out.pose,
                state: out.state,
                reference_levels,
            };
            lock(&s.poses).push(record, is_reference);
        }
        if let Some(tx) = &outputs {
            let mut msg = TrackedFrame {
                sequence: meta.sequence,
                output: out,
            };
            match s.admission {
                Admission::Offline => loop {
                    match tx.send_timeout(msg, Duration::from_millis(50)) {
                        Ok(()) | Err(SendTimeoutError::Disconnected(_)) => break,
                        Err(SendTimeoutError::Timeout(m)) => {
                            if s.aborted() {
                                break;
                            }
                            msg = m;
                        }
                    }
                },
                Admission::Live => {
                    if let Err(TrySendError::Full(_)) = tx.try_send(msg) {
                        s.update_progress(|p| p.outputs_discarded += 1);
                    }
                }
            }
        }
        lock(&s.timers.tracker).record(tracked_in);
        lock(&s.timers.work).record(meta.filtered_in + tracked_in);
        lock(&s.timers.work_cpu).record(meta.filtered_cpu + tracked_cpu);
        lock(&s.timers.latency).record(now.saturating_duration_since(meta.pushed_at));
        s.update_progress(|p| {
            p.tracked += 1;
            p.last_tracked = Some(now);
        });
    }
}

pub(crate) fn geometry_stage(s: &Shared, compute: &rayon::ThreadPool) {
    let (Some(opts), Some(cloud)) = (s.geometry, &s.cloud) else {
        return;
    };
    let stride = opts.point_stride.max(1);
    let per_frame = s.camera.width.div_ceil(stride) * s.camera.height.div_ceil(stride);
    let mut staged = Vec::with_capacity(per_frame);
    while let Some(item) = s.to_geometry.pop() {
        if s.aborted() {
            break;
        }
        s.hook(Stage::Geometry, item.frame.sequence());
        let t0 = Instant::now();
        compute.install(|| stage_points(&item.frame, &item.pose, stride, &mut staged));
        drop(item);
        lock(cloud).extend(&staged);
        lock(&s.timers.geometry).record(t0.elapsed());
        s.update_progress(|p| p.geometry_done += 1);
    }
}
