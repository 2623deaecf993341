package io.ecvo;

import java.io.File;
import java.util.Arrays;
import java.util.Locale;
import java.util.concurrent.atomic.AtomicBoolean;
import java.util.concurrent.atomic.AtomicLong;

/**
 * Soak: FRAMES frames (default 100,000) at 320x180 pushed through libecvo_jni in live
 * mode from one thread (direct buffers, as the app does), at most RATE per second,
 * while a UI-like reader thread polls the pose and state every 16 ms and the
 * trajectory, statistics and point cloud every second. Prints RSS, JVM heap, threads
 * and file descriptors every REPORT frames, then latency percentiles and a verdict.
 *
 * java -Djava.library.path=target/release -cp CLASSES io.ecvo.Soak DATA_DIR [FRAMES] [RATE] [REPORT] [WARMUP]
 */
public final class Soak {
    /** The length of the whole kept trajectory at the reader's last slow poll. */
    private static final AtomicLong maxTrajectory = new AtomicLong();

    public static void main(String[] args) throws Exception {
        Locale.setDefault(Locale.ROOT);
        Frames f = new Frames(new File(args[0]));
        long frames = args.length > 1 ? Long.parseLong(args[1]) : 100_000;
        double rate = args.length > 2 ? Double.parseDouble(args[2]) : 300;
        long report = args.length > 3 ? Long.parseLong(args[3]) : 5_000;
        // Without a WARMUP argument, warm-up ends at the first report at which both the
        // cloud and the tracker's trajectory window are full (poses are being discarded):
        // from then on nothing is meant to grow.
        long warmupArg = args.length > 4 ? Long.parseLong(args[4]) : -1;

        int threads0 = Proc.threads(), fds0 = Proc.fds();
        long handle = NativeBridge.nativeInit(f.width, f.height, f.fx, f.fy, f.cx, f.cy,
                0, 1000.0, 0, 1, 2, true, 2, true);
        Reader r = new Reader(handle);
        Thread reader = new Thread(r, "ui-reader");
        reader.start();

        Pusher pusher = new Pusher(f, handle, frames, rate, report, warmupArg);
        System.out.println("frames\tseconds\tRSS_MB\theap_MB\tthreads\tfds\ttracked\tdropped\tlost\treanchors\ttrajectory\tcloud\tjit_ms");
        pusher.pushAll();
        long[] pushNs = pusher.pushNs;
        long start = pusher.start, warmup = pusher.warmup, rssWarm = pusher.rssWarm, heapWarm = pusher.heapWarm;
        long cloudWarm = pusher.cloudWarm, trackedWarm = pusher.trackedWarm, cloudEnd = pusher.cloudEnd;
        long rssMin = pusher.rssMin, rssMax = pusher.rssMax;
        int threadsWarm = pusher.threadsWarm, fdsWarm = pusher.fdsWarm;
        NativeBridge.nativeFlush(handle);
        double[] s = NativeBridge.nativeStats(handle);
        long rssEnd = Proc.rssKb();
        int threadsEnd = Proc.threads(), fdsEnd = Proc.fds();
        r.done.set(true);
        reader.join();
        // The reader's last read may precede the last frames: read what is left.
        r.received.addAndGet(NativeBridge.nativeTrajectorySince(handle, (int) r.cursor.get()).length / 8);
        double[] traj = NativeBridge.nativeTrajectory(handle);
        NativeBridge.nativeRelease(handle);
        Thread.sleep(200);
        int threadsAfter = Proc.threads(), fdsAfter = Proc.fds();

        long[] p = Arrays.copyOf(pushNs, (int) frames);
        Arrays.sort(p);
        int pc = (int) Math.min(r.poseCount.get(), r.poseNs.length);
        long[] q = Arrays.copyOf(r.poseNs, pc);
        Arrays.sort(q);
        double secs = (System.nanoTime() - start) / 1e9;
        System.out.printf("%n%d frames in %.1f s (%.0f pushed/s); tracked %.0f, dropped %.0f, lost %.0f, re-anchors %.0f%n",
                frames, secs, frames / secs, s[2], s[1], s[6], s[8]);
        System.out.printf("push call (ms): p50 %.3f p95 %.3f p99 %.3f max %.3f%n", pct(p, .5), pct(p, .95), pct(p, .99), p[p.length - 1] / 1e6);
        System.out.printf("getPose+state (ms, %d polls, %d trajectory polls): p50 %.3f p95 %.3f p99 %.3f max %.3f%n",
                r.polls.get(), r.trajectoryPolls.get(), pct(q, .5), pct(q, .95), pct(q, .99), q.length == 0 ? 0 : q[q.length - 1] / 1e6);
        System.out.printf("push-to-pose latency (pipeline, mean ms): %.2f; filter %.2f, tracker %.2f ms/frame%n", s[12], s[9], s[10]);
        // The JNI tracker keeps the latest TRAJECTORY_WINDOW (32,768) poses, so the
        // trajectory stops growing once the window is full, before warm-up ends; so does
        // the cloud (500,000 points reserved).
        long trackedEnd = (long) s[2], kept = traj.length / 8, discarded = (long) s[14];
        System.out.printf("RSS after warm-up (%d frames) %.2f MB, at the end %.2f MB: %+.2f MB (min %.2f, max %.2f after warm-up)%n",
                warmup, rssWarm / 1024.0, rssEnd / 1024.0, (rssEnd - rssWarm) / 1024.0, rssMin / 1024.0, rssMax / 1024.0);
        System.out.printf("poses tracked %d -> %d; kept at the end %d (first index %d); received by the incremental reader %d; cloud %d -> %d points%n",
                trackedWarm, trackedEnd, kept, discarded, r.received.get(), cloudWarm, cloudEnd);
        System.out.printf("JVM heap used after warm-up %.1f MB, at the end %.1f MB%n", heapWarm / 1024.0, Proc.heapUsedKb() / 1024.0);
        System.out.printf("threads: before init %d, after warm-up %d, at the end %d, after release %d; fds: %d, %d, %d, %d%n",
                threads0, threadsWarm, threadsEnd, threadsAfter, fds0, fdsWarm, fdsEnd, fdsAfter);
        if (warmup == Long.MAX_VALUE) System.out.println("warm-up never ended: the window or the cloud never filled");
        boolean ok = warmup < frames && r.error == null && threadsEnd == threadsWarm && fdsEnd == fdsWarm
                && threadsAfter <= threads0 && fdsAfter <= fds0
                && kept == Math.min(trackedEnd, 32_768) && discarded == trackedEnd - kept
                && r.received.get() == trackedEnd;
        if (r.error != null) r.error.printStackTrace(System.out);
        double growthMb = (rssEnd - rssWarm) / 1024.0;
        System.out.printf("RSS growth after warm-up: %.2f MB (limit 1 MB)%n", growthMb);
        ok &= growthMb <= 1.0;
        System.out.println(ok ? "SOAK PASSED" : "SOAK FAILED");
        System.exit(ok ? 0 : 1);
    }

    /**
     * The UI-like reader: polls the pose and state every 16 ms, the new poses
     * incrementally (as the app's SessionController does), and every second the whole
     * kept trajectory, the statistics and 2,000 cloud points. One poll is one small
     * method, compiled early (see {@link Pusher}).
     */
    private static final class Reader implements Runnable {
        final long handle;
        final AtomicBoolean done = new AtomicBoolean(false);
        final AtomicLong polls = new AtomicLong(), trajectoryPolls = new AtomicLong();
        // The index of the next pose to ask for, and how many poses it received (every
        // one, if it polls more often than the window fills).
        final AtomicLong cursor = new AtomicLong(), received = new AtomicLong();
        final long[] poseNs = new long[4_000_000];
        final AtomicLong poseCount = new AtomicLong();
        final float[] m = new float[16];
        volatile Throwable error;
        long lastSlow = System.nanoTime();

        Reader(long handle) { this.handle = handle; }

        @Override
        public void run() {
            try {
                while (!done.get()) {
                    poll();
                    Thread.sleep(16);
                }
            } catch (Throwable e) {
                error = e;
            }
        }

        void poll() {
            long t0 = System.nanoTime();
            long ts = NativeBridge.nativeGetPose(handle, m);
            int state = NativeBridge.nativeState(handle);
            long dt = System.nanoTime() - t0;
            long i = poseCount.getAndIncrement();
            if (i < poseNs.length) poseNs[(int) i] = dt;
            if (ts != Long.MIN_VALUE) {
                for (float v : m) if (!Float.isFinite(v)) throw new AssertionError("non-finite pose " + Arrays.toString(m));
            }
            if (state < 0 || state > 2) throw new AssertionError("state " + state);
            polls.incrementAndGet();
            long from = Math.max(cursor.get(), (long) NativeBridge.nativeStats(handle)[14]);
            double[] fresh = NativeBridge.nativeTrajectorySince(handle, (int) from);
            for (double v : fresh) if (!Double.isFinite(v)) throw new AssertionError("non-finite trajectory value");
            cursor.set(from + fresh.length / 8);
            received.addAndGet(fresh.length / 8);
            if (System.nanoTime() - lastSlow > 1_000_000_000L) {
                lastSlow = System.nanoTime();
                double[] traj = NativeBridge.nativeTrajectory(handle);
                maxTrajectory.set(traj.length / 8);
                NativeBridge.nativeStats(handle);
                NativeBridge.nativePointCloud(handle, 2000);
                trajectoryPolls.incrementAndGet();
            }
        }
    }

    /**
     * The push loop's body and its reports, in small methods: the JVM compiles them
     * during warm-up, and the loop is not in main. (With the loop inside main, HotSpot
     * compiled the whole of main on stack after about 60,000 iterations, its back-edge
     * threshold; that compilation's arena, freed afterwards, stayed in glibc's heap as
     * a 1.5-3.6 MB RSS step that was the driver's, not ecvo's.)
     */
    private static final class Pusher {
        final Frames f;
        final long handle, frames, report, warmupArg;
        final double rate;
        final long[] pushNs;
        final long start = System.nanoTime();
        final java.lang.management.CompilationMXBean jit =
                java.lang.management.ManagementFactory.getCompilationMXBean();
        long warmup = Long.MAX_VALUE, rssWarm = -1, heapWarm = -1, cloudWarm = 0, trackedWarm = 0, cloudEnd = 0;
        long rssMin = Long.MAX_VALUE, rssMax = 0;
        int threadsWarm = -1, fdsWarm = -1;

        Pusher(Frames f, long handle, long frames, double rate, long report, long warmupArg) {
            this.f = f; this.handle = handle; this.frames = frames; this.rate = rate;
            this.report = report; this.warmupArg = warmupArg;
            this.pushNs = new long[(int) frames];
        }

        /** The loop itself in a small method: its on-stack compilation is cheap. */
        void pushAll() throws InterruptedException {
            for (long k = 0; k < frames; k++) push(k);
        }

        void push(long k) throws InterruptedException {
            int i = f.pingPong(k);
            long ts = k * 33_333_333L;
            long t0 = System.nanoTime();
            NativeBridge.nativePushBuffers(handle, ts, f.depthBuffers.get(i), f.intensityBuffers.get(i));
            long t1 = System.nanoTime();
            pushNs[(int) k] = t1 - t0;
            // Pace: no faster than RATE frames per second.
            long due = start + (long) ((k + 1) * 1e9 / rate);
            long wait = due - System.nanoTime();
            if (wait > 0) Thread.sleep(wait / 1_000_000, (int) (wait % 1_000_000));
            if ((k + 1) % report == 0 || k + 1 == frames || k + 1 == warmupArg) report(k);
        }

        void report(long k) {
            double[] s = NativeBridge.nativeStats(handle);
            long cloud = NativeBridge.nativePointCloud(handle, Integer.MAX_VALUE).length / 4;
            cloudEnd = cloud;
            long rss = Proc.rssKb();
            boolean warm = warmupArg >= 0 ? k + 1 == warmupArg : s[14] > 0 && cloud >= 500_000;
            if (warm && warmup == Long.MAX_VALUE) {
                warmup = k + 1;
                cloudWarm = cloud; trackedWarm = (long) s[2];
                rssWarm = rss; heapWarm = Proc.heapUsedKb(); threadsWarm = Proc.threads(); fdsWarm = Proc.fds();
            }
            if (k + 1 >= warmup) { rssMin = Math.min(rssMin, rss); rssMax = Math.max(rssMax, rss); }
            System.out.printf("%d\t%.1f\t%.2f\t%.1f\t%d\t%d\t%.0f\t%.0f\t%.0f\t%.0f\t%d\t%d\t%d%n", k + 1,
                    (System.nanoTime() - start) / 1e9, rss / 1024.0, Proc.heapUsedKb() / 1024.0,
                    Proc.threads(), Proc.fds(), s[2], s[1], s[6], s[8], maxTrajectory.get(), cloud,
                    jit.getTotalCompilationTime());
        }
    }

    private static double pct(long[] sorted, double q) {
        if (sorted.length == 0) return 0;
        return sorted[(int) Math.min(sorted.length - 1, Math.ceil(q * sorted.length) - 1)] / 1e6;
    }
}
