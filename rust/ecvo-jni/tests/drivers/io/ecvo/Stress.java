package io.ecvo;

import java.io.File;
import java.nio.ByteBuffer;
import java.nio.ByteOrder;
import java.util.Locale;
import java.util.Map;
import java.util.TreeMap;
import java.util.concurrent.ConcurrentHashMap;
import java.util.concurrent.ThreadLocalRandom;
import java.util.concurrent.atomic.AtomicBoolean;
import java.util.concurrent.atomic.AtomicLong;
import java.util.concurrent.atomic.AtomicLongArray;
import java.util.concurrent.atomic.LongAdder;

/**
 * Concurrency stress of libecvo_jni: THREADS threads (default 8) for SECONDS (default
 * 120) push (buffers and arrays), poll (pose, state, trajectory, references, stats,
 * point cloud), flush, close (release), reset (release and init again in the same
 * slot) and init trackers in 3 shared slots, with a share of deliberate misuse (wrong
 * sizes, null buffers, bad settings, stale handles). Every exception must be a
 * documented one where it is expected: IllegalArgumentException for bad input (and
 * for a push whose timestamp is not after the previous one, which racing pushes to one
 * tracker cause), IllegalStateException for a released handle. A watchdog fails the run when no
 * operation completes for 15 s (deadlock), printing every thread's stack.
 *
 * java -Xcheck:jni -Djava.library.path=target/release -cp CLASSES io.ecvo.Stress DATA_DIR [SECONDS] [THREADS]
 */
public final class Stress {
    static final int SLOTS = 3;
    static final String[] OPS = {"init", "close", "reset", "pushBuffers", "pushArrays", "getPose", "state",
        "flush", "trajectory", "references", "stats", "pointCloud", "badInput", "staleHandle"};
    static final int[] WEIGHTS = {5, 1, 1, 30, 20, 20, 10, 2, 3, 2, 3, 2, 3, 2};

    static Frames f;
    static final AtomicLongArray slots = new AtomicLongArray(SLOTS);
    static final AtomicLong clock = new AtomicLong();
    static final LongAdder total = new LongAdder();
    static final LongAdder racedTimestamps = new LongAdder();
    static final Map<String, LongAdder> ops = new ConcurrentHashMap<>();
    static final Map<String, LongAdder> exceptions = new ConcurrentHashMap<>();
    static final Map<String, LongAdder> unexpected = new ConcurrentHashMap<>();
    static final Map<String, String> unexpectedSample = new ConcurrentHashMap<>();
    static final AtomicLong lastStale = new AtomicLong(-1);

    static void count(Map<String, LongAdder> m, String key) {
        m.computeIfAbsent(key, k -> new LongAdder()).increment();
    }

    static long init() {
        ThreadLocalRandom r = ThreadLocalRandom.current();
        return NativeBridge.nativeInit(f.width, f.height, f.fx, f.fy, f.cx, f.cy, 0, 1000.0, 0,
                r.nextInt(2), r.nextInt(3), r.nextBoolean(), 1 + r.nextInt(2), r.nextBoolean());
    }

    /** Runs one operation; returns whether IllegalArgumentException is the expected outcome. */
    static boolean op(String name, ThreadLocalRandom r) {
        int s = r.nextInt(SLOTS);
        long h = slots.get(s);
        int i = r.nextInt(f.size());
        switch (name) {
            case "init": {
                if (h != 0) return false;
                long n = init();
                if (!slots.compareAndSet(s, 0, n)) NativeBridge.nativeRelease(n);
                return false;
            }
            case "close": {
                long old = slots.getAndSet(s, 0);
                if (old != 0) { NativeBridge.nativeRelease(old); lastStale.set(old); }
                return false;
            }
            case "reset": {
                long old = slots.getAndSet(s, 0);
                if (old != 0) { NativeBridge.nativeRelease(old); lastStale.set(old); }
                long n = init();
                if (!slots.compareAndSet(s, 0, n)) NativeBridge.nativeRelease(n);
                return false;
            }
            case "pushBuffers": {
                // Each thread its own view: the native side reads from position() to limit(),
                // which are per-view state. duplicate() resets the byte order to BIG_ENDIAN,
                // which the native side refuses for depth, so the order is set again.
                ByteBuffer d = f.depthBuffers.get(i).duplicate().order(ByteOrder.LITTLE_ENDIAN), g = f.intensityBuffers.get(i).duplicate();
                NativeBridge.nativePushBuffers(h, clock.addAndGet(33_333_333L), d, g);
                return false;
            }
            case "pushArrays":
                NativeBridge.nativePushArrays(h, clock.addAndGet(33_333_333L), f.depth.get(i), f.intensity.get(i));
                return false;
            case "getPose": {
                float[] m = new float[16];
                if (NativeBridge.nativeGetPose(h, m) != Long.MIN_VALUE) {
                    for (float v : m) if (!Float.isFinite(v)) throw new AssertionError("non-finite pose");
                }
                return false;
            }
            case "state": {
                int st = NativeBridge.nativeState(h);
                if (st < 0 || st > 2) throw new AssertionError("state " + st);
                return false;
            }
            case "flush": NativeBridge.nativeFlush(h); return false;
            case "trajectory": NativeBridge.nativeTrajectory(h); return false;
            case "references": NativeBridge.nativeReferences(h); return false;
            case "stats": NativeBridge.nativeStats(h); return false;
            case "pointCloud": NativeBridge.nativePointCloud(h, r.nextInt(0, 5000)); return false;
            case "badInput": {
                switch (r.nextInt(6)) {
                    case 0: NativeBridge.nativePushArrays(h, 1, new short[7], new byte[7]); break;
                    case 1: NativeBridge.nativePushBuffers(h, 1, null, f.intensityBuffers.get(0)); break;
                    case 2: NativeBridge.nativePushBuffers(h, 1, ByteBuffer.allocate(2 * f.width * f.height), f.intensityBuffers.get(0)); break;
                    case 3: NativeBridge.nativeGetPose(h, new float[4]); break;
                    case 4: NativeBridge.nativePointCloud(h, -1 - r.nextInt(5)); break;
                    default: NativeBridge.nativeRelease(NativeBridge.nativeInit(-1, 180, 1, 1, 0, 0, 0, 1000, 0, 0, 0, true, 1, false));
                }
                return true;
            }
            case "staleHandle": {
                long stale = r.nextBoolean() ? lastStale.get() : r.nextLong(1L << 40, Long.MAX_VALUE);
                NativeBridge.nativeState(stale);
                return false;
            }
            default: throw new AssertionError(name);
        }
    }

    public static void main(String[] args) throws Exception {
        Locale.setDefault(Locale.ROOT);
        f = new Frames(new File(args[0]));
        int seconds = args.length > 1 ? Integer.parseInt(args[1]) : 120;
        int nThreads = args.length > 2 ? Integer.parseInt(args[2]) : 8;
        int threads0 = Proc.threads(), fds0 = Proc.fds();
        long rss0 = Proc.rssKb();
        int sum = 0;
        for (int w : WEIGHTS) sum += w;
        final int weightSum = sum;
        AtomicBoolean stop = new AtomicBoolean(false);
        Thread[] workers = new Thread[nThreads];
        for (int t = 0; t < nThreads; t++) {
            workers[t] = new Thread(() -> {
                ThreadLocalRandom r = ThreadLocalRandom.current();
                while (!stop.get()) {
                    int x = r.nextInt(weightSum), k = 0;
                    while (x >= WEIGHTS[k]) x -= WEIGHTS[k++];
                    String name = OPS[k];
                    boolean wantIae = false;
                    try {
                        wantIae = op(name, r);
                        if (wantIae) { count(unexpected, name + ": no exception"); }
                    } catch (IllegalArgumentException e) {
                        count(exceptions, "IllegalArgumentException");
                        // Threads pushing to one tracker race between taking a timestamp from
                        // the shared clock and pushing: a later stamp may arrive first, and the
                        // earlier one is refused (documented: timestamps must increase).
                        boolean raced = name.startsWith("push") && String.valueOf(e.getMessage()).contains("is not after the previous frame");
                        if (raced) racedTimestamps.increment();
                        if (!wantIae && !raced && !name.equals("badInput")) { count(unexpected, name + ": " + e); unexpectedSample.putIfAbsent(name, String.valueOf(e)); }
                    } catch (IllegalStateException e) {
                        // A released, unknown or zero handle: documented, from any call but init.
                        count(exceptions, "IllegalStateException");
                        if (name.equals("init")) count(unexpected, name + ": " + e);
                    } catch (Throwable e) {
                        count(exceptions, e.getClass().getName());
                        count(unexpected, name + ": " + e.getClass().getName());
                        unexpectedSample.putIfAbsent(name + e.getClass().getName(), String.valueOf(e));
                    }
                    count(ops, name);
                    total.increment();
                }
            }, "stress-" + t);
            workers[t].start();
        }
        // Watchdog: operations must keep completing.
        long end = System.nanoTime() + seconds * 1_000_000_000L;
        long last = -1, lastChange = System.nanoTime();
        int maxThreads = 0, maxEcvo = 0;
        long started = System.nanoTime(), nextReport = started + 10_000_000_000L;
        while (System.nanoTime() < end) {
            Thread.sleep(1000);
            long now = total.sum();
            maxThreads = Math.max(maxThreads, Proc.threads());
            maxEcvo = Math.max(maxEcvo, Proc.ecvoThreads());
            if (System.nanoTime() >= nextReport) {
                nextReport += 10_000_000_000L;
                System.out.printf("  %3d s: %d operations, RSS %.1f MB, JVM heap committed %.1f MB, %d ecvo threads%n",
                        (System.nanoTime() - started) / 1_000_000_000L, now, Proc.rssKb() / 1024.0,
                        Proc.heapCommittedKb() / 1024.0, Proc.ecvoThreads());
            }
            if (now != last) { last = now; lastChange = System.nanoTime(); }
            if (System.nanoTime() - lastChange > 15_000_000_000L) {
                System.out.println("WATCHDOG: no operation completed for 15 s; stacks:");
                for (Map.Entry<Thread, StackTraceElement[]> e : Thread.getAllStackTraces().entrySet()) {
                    System.out.println(e.getKey());
                    for (StackTraceElement s : e.getValue()) System.out.println("    at " + s);
                }
                System.out.println("STRESS FAILED (deadlock)");
                Runtime.getRuntime().halt(3);
            }
        }
        stop.set(true);
        for (Thread w : workers) {
            w.join(30_000);
            if (w.isAlive()) {
                System.out.println("WATCHDOG: " + w.getName() + " did not stop within 30 s");
                for (StackTraceElement s : w.getStackTrace()) System.out.println("    at " + s);
                System.out.println("STRESS FAILED (deadlock)");
                Runtime.getRuntime().halt(4);
            }
        }
        for (int s = 0; s < SLOTS; s++) {
            long h = slots.getAndSet(s, 0);
            if (h != 0) NativeBridge.nativeRelease(h);
        }
        Thread.sleep(500);
        int threadsEnd = Proc.threads(), fdsEnd = Proc.fds(), ecvoEnd = Proc.ecvoThreads();
        long opsTotal = total.sum();
        System.out.printf("%d threads, %d s: %d operations (%.0f/s)%n", nThreads, seconds, opsTotal, opsTotal / (double) seconds);
        for (Map.Entry<String, LongAdder> e : new TreeMap<>(ops).entrySet()) System.out.printf("  %-12s %d%n", e.getKey(), e.getValue().sum());
        long exc = 0;
        for (LongAdder a : exceptions.values()) exc += a.sum();
        System.out.printf("exceptions: %d%n", exc);
        for (Map.Entry<String, LongAdder> e : new TreeMap<>(exceptions).entrySet()) System.out.printf("  %-28s %d%n", e.getKey(), e.getValue().sum());
        System.out.printf("  of the IllegalArgumentExceptions, pushes refused for a timestamp not after the previous one: %d%n", racedTimestamps.sum());
        long bad = 0;
        for (LongAdder a : unexpected.values()) bad += a.sum();
        System.out.printf("unexpected: %d%n", bad);
        for (Map.Entry<String, LongAdder> e : new TreeMap<>(unexpected).entrySet()) System.out.printf("  %s: %d%n", e.getKey(), e.getValue().sum());
        for (String s : unexpectedSample.values()) System.out.println("  e.g. " + s);
        System.out.printf("threads: %d before, at most %d during, %d after release; fds %d before, %d after; RSS %.1f MB before, %.1f MB after%n",
                threads0, maxThreads, threadsEnd, fds0, fdsEnd, rss0 / 1024.0, Proc.rssKb() / 1024.0);
        System.out.printf("native threads (ecvo-*): at most %d during, %d after release; JVM heap committed %.1f MB after%n",
                maxEcvo, ecvoEnd, Proc.heapCommittedKb() / 1024.0);
        boolean ok = bad == 0 && threadsEnd <= threads0 && fdsEnd <= fds0 && ecvoEnd == 0 && opsTotal > 0;
        System.out.println(ok ? "STRESS PASSED" : "STRESS FAILED");
        System.exit(ok ? 0 : 1);
    }
}
