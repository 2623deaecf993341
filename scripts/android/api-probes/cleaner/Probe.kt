// The API-level check must fail on this dex: java.lang.ref.Cleaner is API 33, minSdk is 26
// (today's use in android-app/tracker/.../Tracker.kt, as one line).
package probe.cleaner

fun probe(): Any = java.lang.ref.Cleaner.create()
