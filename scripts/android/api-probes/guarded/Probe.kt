// The API-level check must pass on this dex: the same call, under an SDK_INT check.
package probe.guarded

import android.os.Build

fun probe(): Any? = if (Build.VERSION.SDK_INT >= 33) java.lang.ref.Cleaner.create() else null
