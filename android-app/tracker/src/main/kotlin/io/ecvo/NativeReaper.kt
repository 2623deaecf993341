package io.ecvo

import java.lang.ref.PhantomReference
import java.lang.ref.ReferenceQueue
import java.util.concurrent.ConcurrentHashMap
import java.util.concurrent.atomic.AtomicBoolean

/**
 * A safety net for native resources that exists on every Android version: a
 * [PhantomReference] per owner on a [ReferenceQueue] drained by one daemon thread (and at
 * each [register]). `java.lang.ref.Cleaner` does the same but exists on Android only
 * from API 33, and the app's minSdk is 26.
 *
 * The action must not reach the owner (it would then never become unreachable). It runs
 * at most once: from [Cleanable.clean] (an explicit close) or on the reaper thread after
 * the owner became phantom-reachable.
 */
internal class NativeReaper(private val threadName: String) {
    /** The handle [register] returns. */
    interface Cleanable {
        /** Runs the action now unless it already ran; unregisters it. */
        fun clean()
    }

    private val queue = ReferenceQueue<Any>()

    /** Keeps the references themselves reachable until their action ran. */
    private val pending: MutableSet<Ref> = ConcurrentHashMap.newKeySet()
    private val started = AtomicBoolean(false)

    private inner class Ref(owner: Any, private val action: Runnable) : PhantomReference<Any>(owner, queue), Cleanable {
        private val done = AtomicBoolean(false)

        override fun clean() {
            if (!done.compareAndSet(false, true)) return
            pending.remove(this)
            clear()
            action.run()
        }
    }

    /** Registrations whose action has not run yet. */
    val pendingCount: Int get() = pending.size

    /** Runs [action] once [owner] is unreachable, unless [Cleanable.clean] ran it first. */
    fun register(owner: Any, action: Runnable): Cleanable {
        drain()
        val r = Ref(owner, action)
        pending.add(r)
        if (started.compareAndSet(false, true)) startThread()
        return r
    }

    /** Runs the actions of owners already collected (without waiting). */
    fun drain() {
        while (true) {
            val r = queue.poll() ?: return
            runQuietly(r)
        }
    }

    private fun startThread() {
        val t = Thread(Reaper(), threadName)
        t.isDaemon = true
        t.start()
    }

    /** The daemon loop (a named class, not a lambda: the APK's dexer cannot desugar lambdas). */
    private inner class Reaper : Runnable {
        override fun run() {
            while (true) {
                val r = try {
                    queue.remove()
                } catch (e: InterruptedException) {
                    continue
                }
                runQuietly(r)
            }
        }
    }

    private fun runQuietly(r: java.lang.ref.Reference<out Any>) {
        try {
            (r as Cleanable).clean()
        } catch (e: Throwable) {
            // An action that throws must not stop the reaper thread.
            if (e is VirtualMachineError) throw e
        }
    }
}
