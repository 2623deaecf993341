package io.ecvo.app

import android.content.Context
import android.os.Build
import io.ecvo.shared.AppSettings
import io.ecvo.shared.CameraIntrinsics
import io.ecvo.shared.StreamMetadata

/** What a recording or an export says about the phone and the app (`metadata.json`). */
object DeviceInfo {
    /** The metadata of a stream of [camera] frames taken with [settings] in [liveMode] (null: a replay). */
    fun metadata(context: Context, settings: AppSettings, liveMode: String?, camera: CameraIntrinsics?): StreamMetadata = StreamMetadata(
        device = "${Build.MANUFACTURER} ${Build.MODEL}",
        android = "Android ${Build.VERSION.RELEASE} (API ${Build.VERSION.SDK_INT})",
        app = appVersion(context),
        settings = settings.toMap(),
        liveMode = liveMode,
        camera = camera,
        gravityUp = GravitySensor.up,
        imuClock = if (GyroSensor.rotationCameraDevice != null) SessionHolder.controller.session?.cameraClock?.method?.label else null,
    )

    private fun appVersion(context: Context): String? = try {
        @Suppress("DEPRECATION")
        context.packageManager.getPackageInfo(context.packageName, 0).versionName
    } catch (e: Exception) {
        null
    }
}
