// :shared — everything of the app that needs no Android API: recording and reading streams
// (PNG codec, camera.json, TUM lists), DEPTH16 decoding, registration of the Y plane to the
// depth frame, trajectory projection and the status presenter. Tested on the JVM.
plugins {
    alias(libs.plugins.kotlin.jvm)
}

kotlin {
    jvmToolchain(libs.versions.jvmTarget.get().toInt())
}

dependencies {
    api(project(":tracker"))
    testImplementation(libs.junit)
}

tasks.test {
    // The tests read testdata/ and, when present, ../shared/datasets.
    systemProperty("ecvo.repo", rootDir.path)
}
