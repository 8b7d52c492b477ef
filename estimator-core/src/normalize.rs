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

/// Number of airspeed bands of a [`TurbulenceEnvelope`].
pub const TURBULENCE_BANDS: usize = 8;

/// The turbulence the training flights flew, by airspeed: per band of the air-data filter's
/// airspeed, the limit of the turbulence index ([`crate::Feature::FilterTurbulence`]) a model was
/// trained on (the trainer takes the 99.9th percentile of the band's training frames).
///
/// A model's single-feature envelopes miss the combination that hurts: training flies its hardest
/// turbulence in fast flight and only light turbulence in slow flight near the α limiter, so each
/// feature alone stays in its range when heavy turbulence meets slow flight. The index is an angle
/// (the wind change over the airspeed), so the same air turns α and β further the slower the
/// aircraft flies. An airspeed below the first band counts in the first, above the last in the last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TurbulenceEnvelope {
    /// Lower edge of the first band, mm/s of filter airspeed.
    pub speed_lo_mms: i32,
    /// Width of each band, mm/s (a width ≤ 0 puts everything in the first band).
    pub band_mms: i32,
    /// Turbulence index limit of each band, µrad.
    pub limit_urad: [i32; TURBULENCE_BANDS],
}

impl TurbulenceEnvelope {
    /// No limit: a model that does not read the filter.
    pub const ANY: TurbulenceEnvelope = TurbulenceEnvelope {
        speed_lo_mms: 0,
        band_mms: 1,
        limit_urad: [i32::MAX; TURBULENCE_BANDS],
    };

    /// The band of a filter airspeed (mm/s).
    pub fn band(&self, speed_mms: i32) -> usize {
        if self.band_mms <= 0 {
            return 0;
        }
        // The difference of two i32 fits i64; the width is positive here.
        let d = i64::from(speed_mms).wrapping_sub(i64::from(self.speed_lo_mms));
        let k = d.checked_div_euclid(i64::from(self.band_mms)).unwrap_or(0);
        k.clamp(0, TURBULENCE_BANDS.saturating_sub(1) as i64) as usize
    }

    /// Whether `turbulence_urad` is above what training saw at filter airspeed `speed_mms`.
    pub fn exceeded(&self, speed_mms: i32, turbulence_urad: i32) -> bool {
        self.limit_urad
            .get(self.band(speed_mms))
            .is_some_and(|l| turbulence_urad > *l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turbulence_bands_clamp_at_both_ends() {
        let e = TurbulenceEnvelope {
            speed_lo_mms: -100,
            band_mms: 50,
            limit_urad: [10, 20, 30, 40, 50, 60, 70, 80],
        };
        assert_eq!(e.band(i32::MIN), 0);
        assert_eq!(e.band(-101), 0);
        assert_eq!(e.band(-100), 0);
        assert_eq!(e.band(-51), 0);
        assert_eq!(e.band(-50), 1);
        assert_eq!(e.band(249), 6);
        assert_eq!(e.band(250), 7);
        assert_eq!(e.band(i32::MAX), 7);
        assert!(!e.exceeded(-50, 20));
        assert!(e.exceeded(-50, 21));
        assert!(e.exceeded(i32::MAX, 81));
        assert!(!TurbulenceEnvelope::ANY.exceeded(0, i32::MAX));
        let flat = TurbulenceEnvelope { band_mms: 0, ..e };
        assert_eq!(flat.band(1_000_000), 0);
    }

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
