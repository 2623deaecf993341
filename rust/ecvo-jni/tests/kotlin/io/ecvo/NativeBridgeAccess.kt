package io.ecvo

/** Reads Tracker's private handle and raw arrays, for tests that call NativeBridge directly. */
internal object NativeBridgeAccess {
    /** Tracker's private `Handle` object (shared with its Cleaner). */
    fun handleObject(t: Tracker): Any {
        val f = Tracker::class.java.getDeclaredField("handle")
        f.isAccessible = true
        return f.get(t)
    }

    /** The native handle held by a `Handle` object (0 once released). */
    fun value(handle: Any): Long {
        val f = handle.javaClass.getDeclaredField("value")
        f.isAccessible = true
        return f.getLong(handle)
    }

    fun handle(t: Tracker): Long = value(handleObject(t))

    fun trajectory(t: Tracker): DoubleArray = NativeBridge.nativeTrajectory(handle(t))
}
