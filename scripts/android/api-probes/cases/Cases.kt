// One function per case; test-api-levels.sh expects a finding exactly in the functions named
// bad*, none in the ones named ok*.
package probe.cases

import android.os.Build
import java.lang.ref.Cleaner

fun okPlain(): Int = java.util.ArrayList<Int>().size

fun okGuarded(): Any? = if (Build.VERSION.SDK_INT >= 33) Cleaner.create() else null

fun okGuardedGreater(): Any? = if (Build.VERSION.SDK_INT > 32) Cleaner.create() else null

fun okEarlyReturn(): Any? {
    if (Build.VERSION.SDK_INT < 33) return null
    return Cleaner.create()
}

fun okReversed(): Any? = if (33 <= Build.VERSION.SDK_INT) Cleaner.create() else null

fun badUnguarded(): Any = Cleaner.create()

fun badWeakGuard(): Any? = if (Build.VERSION.SDK_INT >= 30) Cleaner.create() else null

fun badElseBranch(): Any? = if (Build.VERSION.SDK_INT >= 33) null else Cleaner.create()

fun badAfterGuard(): Any {
    if (Build.VERSION.SDK_INT >= 33) println("new enough")
    return Cleaner.create()
}

/** The AndroidX convention: code in an Api<N>Impl class is checked at level N ... */
object Api33Impl {
    fun make(): Any = Cleaner.create()
}

fun okViaImpl(): Any? = if (Build.VERSION.SDK_INT >= 33) Api33Impl.make() else null

/** ... and a call into it needs the guard itself. */
fun badViaImplUnguarded(): Any = Api33Impl.make()

/** Not in Android at any level. */
fun badNotInAndroid(): Any = java.lang.invoke.LambdaMetafactory::class.java

/** Java 9's covariant ByteBuffer.position(int): ByteBuffer, which Android does not declare. */
fun badCovariantByteBuffer(): Any = java.nio.ByteBuffer.allocate(4).position(1)

/** A class implementing an API 33 interface loads only from 33 on: create it under a guard. */
fun okGuardedApi33Class(): Any? = if (Build.VERSION.SDK_INT >= 33) object : Cleaner.Cleanable {
    override fun clean() {}
} else null

fun badUnguardedApi33Class(): Any = object : Cleaner.Cleanable {
    override fun clean() {}
}
