package io.ecvo.shared

import java.math.BigDecimal
import java.math.RoundingMode

/** Timestamps of recorded streams: seconds with 6 decimals in the lists, nanoseconds in the app. */
object Timestamps {
    /**
     * Formats [ns] nanoseconds as seconds with exactly 6 decimals (`1234.567890`), rounded
     * to the nearest microsecond (halves up), as the lists and file names of a stream use.
     */
    fun formatSeconds(ns: Long): String {
        require(ns >= 0) { "timestamp $ns ns is negative" }
        val us = ns / 1000 + if (ns % 1000 >= 500) 1 else 0
        return "${us / 1_000_000}.${(us % 1_000_000).toString().padStart(6, '0')}"
    }

    /** Microseconds of [ns], rounded as [formatSeconds] rounds. */
    fun roundToMicros(ns: Long): Long = ns / 1000 + if (ns % 1000 >= 500) 1 else 0

    /** Parses a decimal seconds field exactly into nanoseconds (rounded half-even below 1 ns). */
    fun parseSecondsToNs(text: String): Long =
        BigDecimal(text).movePointRight(9).setScale(0, RoundingMode.HALF_EVEN).longValueExact()

    /** A double written in plain decimal notation (no exponent) with round-trip precision. */
    fun plain(v: Double): String {
        require(v.isFinite()) { "$v is not finite" }
        if (v == 0.0) return "0"
        return BigDecimal(v.toString()).stripTrailingZeros().toPlainString()
    }
}
