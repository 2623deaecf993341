// Gradle build of the Android app. The Rust workspace (Cargo.toml) sits beside it at the root;
// the app's modules live under android-app/.
//   :tracker  plain Kotlin/JVM: the Tracker API over libecvo_jni (io.ecvo)
//   :shared   plain Kotlin/JVM: stream recording/reading, PNG, DEPTH16, registration,
//             trajectory projection, UI state (io.ecvo.shared); tested on the JVM
//   :app      the Android application (io.ecvo.app)
// Without an Android SDK, the JVM modules are compiled and tested by scripts/kotlin/test-kotlin.sh.

pluginManagement {
    repositories {
        google {
            content {
                includeGroupByRegex("com\\.android.*")
                includeGroupByRegex("com\\.google.*")
                includeGroupByRegex("androidx.*")
            }
        }
        mavenCentral()
        gradlePluginPortal()
    }
}

plugins {
    // Lets `jvmToolchain(17)` download a JDK 17 when none is installed.
    id("org.gradle.toolchains.foojay-resolver-convention") version "1.0.0"
}

dependencyResolutionManagement {
    repositoriesMode.set(RepositoriesMode.FAIL_ON_PROJECT_REPOS)
    repositories {
        google()
        mavenCentral()
    }
}

rootProject.name = "ecvo"

include(":tracker", ":shared", ":app")
project(":tracker").projectDir = file("android-app/tracker")
project(":shared").projectDir = file("android-app/shared")
project(":app").projectDir = file("android-app/app")
