//! Input normalisation and the training envelope, both in integer arithmetic.

/// `q = clamp(((raw - center) * mult + 2^(shift-1)) >> shift, i16)`: maps a raw feature to the network's
/// int16 input scale (the trainer chooses `mult`/`shift` so one training standard deviation is 4096).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Norm {
    pub center: i32,
    pub mult: i32,
    pub shift: u8,
}

/// Network input value of one training standard deviation.
pub const ONE_SIGMA: i32 = 4096;

impl Norm {
    /// Exact for every input, in i64: |raw - center| < 2^32 and |mult| <= 2^31, so the product
    /// stays below 2^63 in magnitude (the wrapping ops never wrap). The rounding is done as
    /// `((p >> (shift - 1)) + 1) >> 1`, which equals `(p + 2^(shift-1)) >> shift` for every `p` but
    /// cannot overflow where that sum could (shifts above 32 with a feature spanning nearly all of i32).
    #[inline]
    pub fn apply(self, raw: i32) -> i16 {
        let shift = (self.shift as u32).clamp(1, 62);
        let d = i64::from(raw).wrapping_sub(i64::from(self.center));
        let p = d.wrapping_mul(i64::from(self.mult));
        let v = (p >> shift.wrapping_sub(1)).wrapping_add(1) >> 1;
        v.clamp(i16::MIN as i64, i16::MAX as i64) as i16
    }
}

/// Inclusive range of a raw value seen in training.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Envelope {
    pub lo: i32,
    pub hi: i32,
}

impl Envelope {
    pub const ANY: Envelope = Envelope {
        lo: i32::MIN,
        hi: i32::MAX,
    };

    /// The value clamped into the envelope, and whether it was outside.
    #[inline]
    pub fn clamp(self, v: i32) -> (i32, bool) {
        if v < self.lo {
            (self.lo, true)
        } else if v > self.hi {
            (self.hi, true)
        } else {
            (v, false)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norm_rounds_and_saturates() {
        let n = Norm {
            center: 100,
            mult: 3,
            shift: 1,
        }; // (x-100)*1.5
        assert_eq!(n.apply(100), 0);
        assert_eq!(n.apply(101), 2); // 1.5 rounds up
        assert_eq!(n.apply(99), -1); // -1.5 rounds toward +inf
        assert_eq!(n.apply(i32::MAX), i16::MAX);
        assert_eq!(n.apply(i32::MIN), i16::MIN);
    }

    /// The formula in i128, where nothing can overflow.
    fn reference(n: Norm, raw: i32) -> i16 {
        let shift = (n.shift as u32).clamp(1, 62);
        let p = (raw as i128 - n.center as i128) * n.mult as i128;
        let v = (p + (1i128 << (shift - 1))) >> shift;
        v.clamp(i16::MIN as i128, i16::MAX as i128) as i16
    }

    #[test]
    fn norm_is_exact_at_the_extremes() {
        for raw in [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX] {
            for center in [i32::MIN, -1, 0, 1, i32::MAX] {
                for mult in [i32::MIN, -1, 0, 1, 1 << 30, i32::MAX] {
                    for shift in [0, 1, 2, 31, 32, 33, 47, 48, 49, 61, 62, 63, 255] {
                        let n = Norm {
                            center,
                            mult,
                            shift,
                        };
                        assert_eq!(n.apply(raw), reference(n, raw), "{n:?} raw={raw}");
                    }
                }
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn norm_is_the_formula(raw: i32, center: i32, mult: i32, shift: u8) {
            let n = Norm { center, mult, shift };
            proptest::prop_assert_eq!(n.apply(raw), reference(n, raw));
        }
    }

    #[test]
    fn envelope_clamps_and_reports() {
        let e = Envelope { lo: -5, hi: 5 };
        assert_eq!(e.clamp(3), (3, false));
        assert_eq!(e.clamp(-9), (-5, true));
        assert_eq!(e.clamp(9), (5, true));
    }
}
