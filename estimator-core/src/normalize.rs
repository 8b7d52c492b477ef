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
    #[inline]
    pub fn apply(self, raw: i32) -> i16 {
        let shift = (self.shift as u32).clamp(1, 62);
        let d = raw as i64 - self.center as i64;
        let v = (d * self.mult as i64 + (1i64 << (shift - 1))) >> shift;
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

    #[test]
    fn envelope_clamps_and_reports() {
        let e = Envelope { lo: -5, hi: 5 };
        assert_eq!(e.clamp(3), (3, false));
        assert_eq!(e.clamp(-9), (-5, true));
        assert_eq!(e.clamp(9), (5, true));
    }
}
