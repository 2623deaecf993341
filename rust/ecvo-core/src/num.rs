//! Numbers in messages: [`Num`] shows an `f64` as it would be written, `517.3`,
//! `0.02`, `-1`, and in scientific notation when it is very large or very small
//! (`1e300`, `1.5e-7`), never as a 300-digit decimal. The shortest text that reads
//! back as the same `f64` (the `zmij` algorithm, as `serde_json` writes numbers).

use std::fmt;

/// An `f64` displayed for a person: the shortest round-trip text, with an exponent
/// when its magnitude is below 1e-5 or at least 1e16; `NaN`, `inf` and `-inf` as
/// such. `format!("{}", Num(1e300))` is `1e300`, `Num(517.3)` is `517.3`,
/// `Num(-2.0)` is `-2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v.is_nan() {
            return f.pad("NaN");
        }
        if v.is_infinite() {
            return f.pad(if v > 0.0 { "inf" } else { "-inf" });
        }
        let mut buf = zmij::Buffer::new();
        let s = buf.format_finite(v);
        // zmij writes integers as `2.0` and exponents as `e+300`; a person writes `2`
        // and `1e300`.
        let s = s.strip_suffix(".0").unwrap_or(s);
        match s.split_once("e+") {
            Some((m, e)) => f.pad(&format!("{m}e{e}")),
            None => f.pad(s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Num;

    #[test]
    fn numbers_are_shown_as_written_or_with_an_exponent() {
        for (v, want) in [
            (517.3, "517.3"),
            (0.02, "0.02"),
            (-2.0, "-2"),
            (0.0, "0"),
            (5000.0, "5000"),
            (1e300, "1e300"),
            (-1e300, "-1e300"),
            (1.5e-7, "1.5e-7"),
            (1e16, "1e16"),
            (123456789012345.0, "123456789012345"),
            (f64::MAX, "1.7976931348623157e308"),
            (f64::NAN, "NaN"),
            (f64::INFINITY, "inf"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(Num(v).to_string(), want, "{v:?}");
        }
    }
}
