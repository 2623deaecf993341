package io.ecvo;

import java.nio.ByteBuffer;

/**
 * A Java twin of android-app's Kotlin {@code io.ecvo.NativeBridge} (same class name,
 * same static native methods, hence the same JNI symbols) for the soak and stress
 * drivers, which run on a bare JVM without kotlinc. The signatures are checked
 * against the Rust declarations by {@code tests/it/signatures.rs} (JNI binds the short
 * names, which carry no signature: a missing parameter would be read as garbage).
 */
public final class NativeBridge {
    static {
        System.loadLibrary("ecvo_jni");
    }

    private NativeBridge() {}

    public static native long nativeInit(int width, int height, double fx, double fy, double cx, double cy,
            int depthFormat, double depthScale, int minConfidence, int preset, int mode, boolean live, int threads,
            boolean pointCloud);
    public static native int nativePushBuffers(long handle, long timestampNs, ByteBuffer depth, ByteBuffer intensity);
    public static native int nativePushArrays(long handle, long timestampNs, short[] depth, byte[] intensity);
    public static native long nativeGetPose(long handle, float[] out);
    public static native int nativeState(long handle);
    public static native void nativeFlush(long handle);
    public static native void nativeSetIntrinsics(long handle, double fx, double fy, double cx, double cy);
    public static native double[] nativeTrajectory(long handle);
    public static native double[] nativeTrajectorySince(long handle, int from);
    public static native double[] nativeReferences(long handle);
    public static native double[] nativeStats(long handle);
    public static native float[] nativePointCloud(long handle, int maxPoints);
    public static native void nativeRelease(long handle);
    public static native long nativeMemoryNeeded(int width, int height, double fx, double fy, double cx, double cy,
            int depthFormat, double depthScale, int minConfidence, int preset, int mode, boolean live, int threads,
            boolean pointCloud);
    public static native long nativeSetMemoryBudget(long bytes);
}
