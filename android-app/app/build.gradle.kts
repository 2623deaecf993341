// :app — the Android application: replays a recorded stream or tracks live from a DEPTH16
// camera and draws the trajectory. Everything that can be plain Kotlin lives in :shared.
plugins {
    alias(libs.plugins.android.application)
    alias(libs.plugins.kotlin.android)
}

/** The ABIs libecvo_jni is built for (by cargo-ndk) and packaged for. */
val ecvoAbis = listOf("arm64-v8a", "armeabi-v7a", "x86_64")
val jniLibsDir = layout.projectDirectory.dir("src/main/jniLibs") // generated, git-ignored

android {
    namespace = "io.ecvo.app"
    compileSdk = libs.versions.compileSdk.get().toInt()
    ndkVersion = libs.versions.ndk.get()

    defaultConfig {
        applicationId = "io.ecvo.app"
        minSdk = libs.versions.minSdk.get().toInt()
        targetSdk = libs.versions.targetSdk.get().toInt()
        versionCode = 1
        versionName = "0.1.0"
        ndk {
            abiFilters += ecvoAbis
        }
    }

    buildTypes {
        release {
            isMinifyEnabled = false
            // Signed with the debug key so that a release build installs for testing; use a
            // real signing config to publish.
            signingConfig = signingConfigs.getByName("debug")
        }
    }

    compileOptions {
        sourceCompatibility = JavaVersion.VERSION_17
        targetCompatibility = JavaVersion.VERSION_17
    }

    sourceSets {
        getByName("main") {
            jniLibs.srcDir(jniLibsDir)
            // The sample stream (written by ecvo-synth, see testdata/README.md) is bundled at
            // the root of the APK's assets: camera.json, rgb.txt, depth.txt, rgb/, depth/.
            assets.srcDir(rootProject.layout.projectDirectory.dir("testdata/synth_phone_320x180"))
        }
    }

    packaging {
        jniLibs {
            // Keep the .so files uncompressed and page-aligned in the APK, loaded in place.
            useLegacyPackaging = false
        }
    }

    androidResources {
        // The sample's PNGs are already compressed.
        noCompress += listOf("png")
    }
}

kotlin {
    jvmToolchain(libs.versions.jvmTarget.get().toInt())
}

// No AndroidX: the app uses platform classes and themes only, so CI can compile its resources
// (aapt) and Kotlin (against generated API stubs) without the SDK; see scripts/android-stubs.
dependencies {
    implementation(project(":tracker"))
    implementation(project(":shared"))
}

/**
 * Builds libecvo_jni for every ABI into src/main/jniLibs with scripts/build-android.sh
 * (cargo-ndk; needs cargo-ndk and the rustup targets). The NDK is the one AGP resolves for
 * `ndkVersion` (installed by the SDK manager in a stock Android Studio), passed to the script
 * as ANDROID_NDK_HOME; an ANDROID_NDK_HOME already set in the environment wins. Skip it with
 * -Pecvo.skipRustBuild=true to package libraries built beforehand.
 */
val agpNdkDirectory = androidComponents.sdkComponents.ndkDirectory
val skipRustBuild = providers.gradleProperty("ecvo.skipRustBuild").map { it.toBoolean() }.orElse(false)
val buildRustLibraries by tasks.registering(Exec::class) {
    group = "build"
    description = "Builds libecvo_jni.so with cargo-ndk for ${ecvoAbis.joinToString()}"
    val root = rootProject.layout.projectDirectory
    onlyIf { !skipRustBuild.get() }
    workingDir = root.asFile
    doFirst {
        if (System.getenv("ANDROID_NDK_HOME").isNullOrBlank()) {
            environment("ANDROID_NDK_HOME", agpNdkDirectory.get().asFile.absolutePath)
        }
    }
    commandLine(
        "bash", root.file("scripts/build-android.sh").asFile.path,
        "-P", libs.versions.minSdk.get(),
        "-o", jniLibsDir.asFile.path,
        *ecvoAbis.flatMap { listOf("-t", it) }.toTypedArray(),
    )
    // cargo decides what to rebuild; these let Gradle skip the task when nothing changed.
    inputs.files(root.file("Cargo.toml"), root.file("Cargo.lock"), root.file("scripts/build-android.sh"))
    inputs.files(fileTree(root.dir("rust")) { include("**/*.rs", "**/Cargo.toml") })
    inputs.property("abis", ecvoAbis)
    outputs.dir(jniLibsDir)
}

tasks.named("preBuild") {
    dependsOn(buildRustLibraries)
}
