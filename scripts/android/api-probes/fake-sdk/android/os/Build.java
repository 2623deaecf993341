// Compile-time stand-in for android.os.Build (the probes' classpath only, never dexed).
package android.os;

public class Build {
    public static class VERSION {
        public static int SDK_INT;
    }
}
