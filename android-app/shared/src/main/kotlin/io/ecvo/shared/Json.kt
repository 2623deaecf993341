package io.ecvo.shared

/**
 * A minimal JSON reader for the small files of a recorded stream (`camera.json`); plain
 * Kotlin, since the JVM has no JSON parser and Android's org.json is not on the JVM.
 * Objects become `Map<String, Any?>`, arrays `List<Any?>`, numbers `Double`.
 */
internal class Json private constructor(private val s: String) {
    private var i = 0

    companion object {
        /** Parses one JSON value; throws IllegalArgumentException with the offset on bad input. */
        fun parse(text: String): Any? {
            val p = Json(text)
            p.ws()
            val v = p.value()
            p.ws()
            if (p.i != text.length) p.fail("unexpected text after the value")
            return v
        }
    }

    private fun fail(msg: String): Nothing = throw IllegalArgumentException("JSON at offset $i: $msg")

    private fun ws() {
        while (i < s.length && s[i] in " \t\r\n") i++
    }

    private fun value(): Any? {
        if (i >= s.length) fail("unexpected end")
        return when (val c = s[i]) {
            '{' -> obj()
            '[' -> arr()
            '"' -> str()
            't' -> lit("true", true)
            'f' -> lit("false", false)
            'n' -> lit("null", null)
            else -> if (c == '-' || c in '0'..'9') num() else fail("unexpected '$c'")
        }
    }

    private fun lit(word: String, v: Any?): Any? {
        if (!s.startsWith(word, i)) fail("expected $word")
        i += word.length
        return v
    }

    private fun obj(): Map<String, Any?> {
        val m = LinkedHashMap<String, Any?>()
        i++
        ws()
        if (i < s.length && s[i] == '}') { i++; return m }
        while (true) {
            ws()
            if (i >= s.length || s[i] != '"') fail("expected a field name")
            val k = str()
            ws()
            if (i >= s.length || s[i] != ':') fail("expected ':'")
            i++
            ws()
            m[k] = value()
            ws()
            if (i >= s.length) fail("unexpected end in object")
            when (s[i++]) {
                ',' -> continue
                '}' -> return m
                else -> { i--; fail("expected ',' or '}'") }
            }
        }
    }

    private fun arr(): List<Any?> {
        val l = ArrayList<Any?>()
        i++
        ws()
        if (i < s.length && s[i] == ']') { i++; return l }
        while (true) {
            ws()
            l.add(value())
            ws()
            if (i >= s.length) fail("unexpected end in array")
            when (s[i++]) {
                ',' -> continue
                ']' -> return l
                else -> { i--; fail("expected ',' or ']'") }
            }
        }
    }

    private fun str(): String {
        val b = StringBuilder()
        i++
        while (true) {
            if (i >= s.length) fail("unterminated string")
            val c = s[i++]
            when (c) {
                '"' -> return b.toString()
                '\\' -> {
                    if (i >= s.length) fail("unterminated string")
                    when (val e = s[i++]) {
                        '"', '\\', '/' -> b.append(e)
                        'b' -> b.append('\b'); 'f' -> b.append('\u000C'); 'n' -> b.append('\n')
                        'r' -> b.append('\r'); 't' -> b.append('\t')
                        'u' -> {
                            if (i + 4 > s.length) fail("bad \\u escape")
                            b.append(s.substring(i, i + 4).toIntOrNull(16)?.toChar() ?: fail("bad \\u escape"))
                            i += 4
                        }
                        else -> fail("bad escape \\$e")
                    }
                }
                else -> b.append(c)
            }
        }
    }

    private fun num(): Double {
        val start = i
        if (s[i] == '-') i++
        while (i < s.length && (s[i].isDigit() || s[i] in ".eE+-")) i++
        val t = s.substring(start, i)
        if (!Regex("-?(0|[1-9][0-9]*)(\\.[0-9]+)?([eE][+-]?[0-9]+)?").matches(t)) { i = start; fail("bad number '$t'") }
        return t.toDouble()
    }
}
