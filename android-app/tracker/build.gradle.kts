// :tracker — the Kotlin API of libecvo_jni. Plain Kotlin/JVM (no Android dependency), so it
// compiles and its tests run on any JVM; the app packages the native library itself.
plugins {
    alias(libs.plugins.kotlin.jvm)
}

kotlin {
    jvmToolchain(libs.versions.jvmTarget.get().toInt())
}

dependencies {
    testImplementation(libs.junit)
}

tasks.test {
    // With -Pecvo.nativeLibDir=<folder with a host build of libecvo_jni>, the JNI tests run
    // against it under -Xcheck:jni (as scripts/kotlin/test-kotlin.sh --native-lib does).
    val nativeDir = providers.gradleProperty("ecvo.nativeLibDir").orNull
    if (!nativeDir.isNullOrBlank()) {
        systemProperty("java.library.path", nativeDir)
        systemProperty("ecvo.native", nativeDir)
        jvmArgs("-Xcheck:jni")
    }
    systemProperty("ecvo.repo", rootDir.path)
}
