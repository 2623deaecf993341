//! Android `DEPTH16` samples: 13-bit millimetres and a 3-bit confidence, and the rule
//! that decides which confidence levels to keep.

use std::sync::atomic::{AtomicBool, Ordering};

/// Decodes one Android `DEPTH16` sample: range in millimetres in the low 13 bits, a
/// 3-bit confidence on top (raw 0 = 100 %, 1 = 0 %, `c` = `(c - 1) / 7`), mapped to a
/// level 0..=7 (7 best: raw 0 -> 7, raw c -> c - 1, as `Depth16.kt` does). Samples
/// whose level is below `min_confidence` become 0 (no measurement).
pub fn decode_depth16(raw: u16, min_confidence: u8) -> u16 {
    let c = raw >> 13;
    let level = if c == 0 { 7 } else { c - 1 };
    if level < u16::from(min_confidence) {
        0
    } else {
        raw & 0x1FFF
    }
}

/// The documented level [`Confidence::Auto`] starts from: drops raw code 1 ("0 %").
pub const AUTO_MIN_LEVEL: u8 = 1;

/// Which `DEPTH16` confidence levels a tracker keeps (`minConfidence` of `nativeInit`:
/// 0..=7 is [`Confidence::Documented`], -1 is [`Confidence::Auto`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Confidence {
    /// Keep levels at or above this one (Android's documented reading of the codes).
    Documented(u8),
    /// Keep levels at or above [`AUTO_MIN_LEVEL`], unless that would drop more than half
    /// of a frame's ranged pixels: such a sensor does not follow the documentation (real
    /// ToF phones mark most good pixels with code 1), and from that frame on every
    /// ranged pixel is kept. Mirrors `ConfidencePolicy.AUTO` of the app.
    Auto,
}

/// How many pixels of one frame had a range and how many were kept.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecodeCounts {
    /// Pixels with a non-zero range.
    pub ranged: usize,
    /// Pixels kept (a range, and a confidence the rule accepts).
    pub kept: usize,
}

/// Decodes whole frames under a [`Confidence`] rule; [`Confidence::Auto`]'s verdict
/// sticks for the decoder's life (one tracker), so frames do not flicker between rules.
#[derive(Debug)]
pub struct Depth16Decoder {
    rule: Confidence,
    codes_ignored: AtomicBool,
}

impl Depth16Decoder {
    /// A decoder for `rule`.
    pub fn new(rule: Confidence) -> Self {
        Depth16Decoder {
            rule,
            codes_ignored: AtomicBool::new(false),
        }
    }

    /// Whether [`Confidence::Auto`] has decided to ignore the confidence codes.
    pub fn codes_ignored(&self) -> bool {
        self.codes_ignored.load(Ordering::Relaxed)
    }

    /// Replaces raw samples by millimetres (0 = no measurement) in place.
    pub fn decode_in_place(&self, depth: &mut [u16]) -> DecodeCounts {
        let min = match self.rule {
            Confidence::Documented(m) => m,
            Confidence::Auto => {
                if !self.codes_ignored() {
                    let ranged = depth.iter().filter(|v| **v & 0x1FFF != 0).count();
                    let confident = depth
                        .iter()
                        .filter(|v| decode_depth16(**v, AUTO_MIN_LEVEL) != 0)
                        .count();
                    if confident * 2 < ranged {
                        self.codes_ignored.store(true, Ordering::Relaxed);
                        log::warn!(
                            "ecvo-jni: DEPTH16 confidence codes ignored: level >= {AUTO_MIN_LEVEL} keeps {confident} of {ranged} ranged pixels"
                        );
                    }
                }
                if self.codes_ignored() {
                    0
                } else {
                    AUTO_MIN_LEVEL
                }
            }
        };
        let mut counts = DecodeCounts::default();
        for v in depth.iter_mut() {
            if *v & 0x1FFF != 0 {
                counts.ranged += 1;
            }
            *v = decode_depth16(*v, min);
            if *v != 0 {
                counts.kept += 1;
            }
        }
        counts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth16_confidence_levels() {
        // Raw confidence 0 is 100 % (level 7), 1 is 0 % (level 0).
        assert_eq!(decode_depth16(1234, 7), 1234);
        assert_eq!(decode_depth16((1 << 13) | 1234, 0), 1234);
        assert_eq!(decode_depth16((1 << 13) | 1234, 1), 0);
        // Raw 5 is level 4.
        assert_eq!(decode_depth16((5 << 13) | 0x1FFF, 4), 0x1FFF);
        assert_eq!(decode_depth16((5 << 13) | 0x1FFF, 5), 0);
    }

    #[test]
    fn auto_keeps_documented_levels_until_most_would_go_then_sticks() {
        let d = Depth16Decoder::new(Confidence::Auto);
        // 3 of 4 ranged pixels are confident: documented rule, code 1 dropped.
        let mut f = [1000, 1000, 1000, (1 << 13) | 1000, 0];
        assert_eq!(
            d.decode_in_place(&mut f),
            DecodeCounts { ranged: 4, kept: 3 }
        );
        assert_eq!(f, [1000, 1000, 1000, 0, 0]);
        assert!(!d.codes_ignored());
        // 3 of 4 at code 1: the codes do not follow the documentation, keep all...
        let mut g = [(1 << 13) | 900, (1 << 13) | 901, (1 << 13) | 902, 903];
        assert_eq!(d.decode_in_place(&mut g).kept, 4);
        assert_eq!(g, [900, 901, 902, 903]);
        // ...and from then on, even for a frame that would pass the documented rule.
        let mut h = [1000, 1000, (1 << 13) | 1000];
        assert_eq!(d.decode_in_place(&mut h).kept, 3);
        assert!(d.codes_ignored());
        let strict = Depth16Decoder::new(Confidence::Documented(1));
        let mut g = [(1 << 13) | 900, (1 << 13) | 901, (1 << 13) | 902, 903];
        assert_eq!(strict.decode_in_place(&mut g).kept, 1);
    }
}
