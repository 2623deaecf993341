package io.ecvo;

import java.io.File;
import java.io.IOException;
import java.nio.file.Files;

/** This process's resident memory, threads and file descriptors, from /proc/self. */
final class Proc {
    private Proc() {}

    static long rssKb() {
        try {
            for (String l : Files.readAllLines(new File("/proc/self/status").toPath())) {
                if (l.startsWith("VmRSS:")) return Long.parseLong(l.replaceAll("[^0-9]", ""));
            }
        } catch (IOException e) {
            return -1;
        }
        return -1;
    }

    static int threads() {
        String[] t = new File("/proc/self/task").list();
        return t == null ? -1 : t.length;
    }

    /** Threads whose name starts with "ecvo-": the native trackers' stage and compute threads. */
    static int ecvoThreads() {
        String[] t = new File("/proc/self/task").list();
        if (t == null) return -1;
        int n = 0;
        for (String id : t) {
            try {
                if (Files.readString(new File("/proc/self/task/" + id + "/comm").toPath()).startsWith("ecvo-")) n++;
            } catch (IOException e) {
                // The thread exited meanwhile.
            }
        }
        return n;
    }

    /** The JVM heap's committed size (what the heap holds of RSS at most). */
    static long heapCommittedKb() {
        return Runtime.getRuntime().totalMemory() / 1024;
    }

    static int fds() {
        String[] f = new File("/proc/self/fd").list();
        return f == null ? -1 : f.length;
    }

    static long heapUsedKb() {
        Runtime r = Runtime.getRuntime();
        return (r.totalMemory() - r.freeMemory()) / 1024;
    }
}
