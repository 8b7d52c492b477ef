use super::{Layer, MAX_IN, kernel, max_products};

/// Requantization of one output channel: `y = ((acc * mult + 2^(shift-1)) >> shift) + offset`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Requant {
    /// Non-negative fixed-point multiplier.
    pub mult: i32,
    /// Right shift, 1..=62.
    pub shift: u8,
    /// Added after the shift, in output units (used by output layers to restore a mean).
    pub offset: i32,
}

impl Requant {
    /// Identity: `y = acc`.
    pub const ONE: Requant = Requant {
        mult: 1 << 30,
        shift: 30,
        offset: 0,
    };

    /// Nothing here can wrap: |acc × mult| <= 2^62, the rounding term is at most 2^61, and the shifted
    /// value plus an i32 offset stays far inside i64 (the wrapping ops change nothing).
    #[inline(always)]
    pub fn apply(self, acc: i32) -> i64 {
        let shift = (self.shift as u32).clamp(1, 62);
        let prod = i64::from(acc)
            .wrapping_mul(i64::from(self.mult))
            .wrapping_add(1i64 << shift.wrapping_sub(1));
        (prod >> shift).wrapping_add(i64::from(self.offset))
    }

    /// [`Requant::apply`] saturated to int32, computed in 32 bits for the usual shifts (33..=62):
    /// the rounding term 2^(shift-1) then only touches the high word of the product, and flooring by
    /// 2^32 then by 2^(shift-32) is flooring by 2^shift, so no 64-bit add or shift is needed. The
    /// product is at most 2^62 in magnitude, so its high word and the rounding sum fit in 31 bits.
    #[inline(always)]
    pub fn apply_sat(self, acc: i32) -> i32 {
        let prod = i64::from(acc).wrapping_mul(i64::from(self.mult)); // |prod| <= 2^62: exact
        let k = (self.shift as u32).wrapping_sub(32);
        if (1..=30).contains(&k) {
            let hi = (prod >> 32) as i32;
            return (hi.wrapping_add(1 << k.wrapping_sub(1)) >> k).saturating_add(self.offset);
        }
        apply_sat_64(acc, self.mult, self.shift, self.offset)
    }
}

/// [`Requant::apply_sat`] for shifts outside 33..=62, in 64 bits: out of line, as it is rare (and
/// with scalar arguments, so that calling it does not spill the `Requant` to the stack).
#[cold]
#[inline(never)]
fn apply_sat_64(acc: i32, mult: i32, shift: u8, offset: i32) -> i32 {
    let rq = Requant {
        mult,
        shift,
        offset,
    };
    rq.apply(acc).clamp(i32::MIN as i64, i32::MAX as i64) as i32
}

/// Weights, bias and requantization of one fully connected layer.
///
/// The shape is part of the type, so a table of another shape does not compile. A layer of three
/// inputs and two outputs takes two rows of three weights, two biases and two requantizations, as
/// the generated weights files declare their layers:
/// ```
/// use estimator_core::nn::{Dense, Requant};
/// static LAYER: Dense<3, 2> = Dense::new([[1, 2, 3], [4, 5, 6]], [0, 0], [Requant::ONE; 2]);
/// ```
/// A weight table of the wrong length (a row missing) does not compile:
/// ```compile_fail,E0308
/// use estimator_core::nn::{Dense, Requant};
/// static LAYER: Dense<3, 2> = Dense::new([[1, 2, 3]], [0, 0], [Requant::ONE; 2]);
/// ```
/// nor do rows of the wrong width:
/// ```compile_fail,E0308
/// use estimator_core::nn::{Dense, Requant};
/// static LAYER: Dense<3, 2> = Dense::new([[1, 2], [4, 5]], [0, 0], [Requant::ONE; 2]);
/// ```
pub struct Dense<const IN: usize, const OUT: usize> {
    /// The int8 weights (-127..=127) in this build's storage format ([`kernel::Weights`]).
    weights: kernel::Weights<IN, OUT>,
    /// Bias in accumulator units.
    pub bias: [i32; OUT],
    // The requantization, field by field: 9 bytes per output instead of the 12 of a padded
    // `Requant` (6 KB of flash on the paper-size network).
    mult: [i32; OUT],
    offset: [i32; OUT],
    shift: [u8; OUT],
}

impl<const IN: usize, const OUT: usize> Dense<IN, OUT> {
    /// Builds a layer, refusing (at compile time when used in a `static`) shapes and values that could
    /// overflow the int32 accumulator or break the symmetric int8 range.
    // Indexing and arithmetic here run in const evaluation for the generated statics: out of bounds
    // or an overflow is a compile error there.
    #[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)]
    pub const fn new(weights: [[i8; IN]; OUT], bias: [i32; OUT], requant: [Requant; OUT]) -> Self {
        assert!(
            IN > 0 && OUT > 0,
            "layers need at least one input and one output"
        );
        assert!(
            IN <= MAX_IN,
            "layer input wider than MAX_IN: the int32 accumulator could overflow"
        );
        let headroom = i32::MAX as i64 - max_products(IN);
        let (mut mult, mut offset, mut shift) = ([0i32; OUT], [0i32; OUT], [0u8; OUT]);
        let mut o = 0;
        while o < OUT {
            let b = bias[o] as i64;
            assert!(
                b <= headroom && -b <= headroom,
                "bias too large for the accumulator head-room"
            );
            assert!(requant[o].mult >= 0, "requant multipliers are non-negative");
            assert!(
                requant[o].shift >= 1 && requant[o].shift <= 62,
                "requant shift out of 1..=62"
            );
            mult[o] = requant[o].mult;
            offset[o] = requant[o].offset;
            shift[o] = requant[o].shift;
            let mut i = 0;
            while i < IN {
                assert!(
                    weights[o][i] != i8::MIN,
                    "weights are symmetric int8: -128 is not used"
                );
                i += 1;
            }
            o += 1;
        }
        Dense {
            weights: kernel::Weights::new(&weights),
            bias,
            mult,
            offset,
            shift,
        }
    }

    /// Multiply-accumulates per forward pass (computed at compile time).
    const MACS: usize = IN * OUT;

    /// The requantizations in output order.
    #[inline(always)]
    fn requants(&self) -> impl Iterator<Item = Requant> + '_ {
        self.mult
            .iter()
            .zip(self.shift.iter())
            .zip(self.offset.iter())
            .map(|((mult, shift), offset)| Requant {
                mult: *mult,
                shift: *shift,
                offset: *offset,
            })
    }

    /// Int32 accumulators with the bias, using the kernel of this build's weight storage.
    #[inline]
    pub fn accumulate(&self, x: &[i16; IN], acc: &mut [i32; OUT]) {
        self.weights.accumulate(&self.bias, x, acc);
    }
}

/// A hidden layer: requantize, ReLU, saturate to int16.
pub struct Hidden<const IN: usize, const OUT: usize>(pub Dense<IN, OUT>);

/// An output layer: requantize to int32 (no activation).
pub struct Output<const IN: usize, const OUT: usize>(pub Dense<IN, OUT>);

impl<const IN: usize, const OUT: usize> Layer<IN, OUT> for Hidden<IN, OUT> {
    type Out = i16;

    #[inline]
    fn forward(&self, x: &[i16; IN], y: &mut [i16; OUT]) {
        let mut acc = [0i32; OUT];
        self.0.accumulate(x, &mut acc);
        for ((y, a), rq) in y.iter_mut().zip(acc.iter()).zip(self.0.requants()) {
            *y = rq.apply_sat(*a).clamp(0, i16::MAX as i32) as i16;
        }
    }

    fn macs(&self) -> usize {
        Dense::<IN, OUT>::MACS
    }
}

impl<const IN: usize, const OUT: usize> Layer<IN, OUT> for Output<IN, OUT> {
    type Out = i32;

    #[inline]
    fn forward(&self, x: &[i16; IN], y: &mut [i32; OUT]) {
        let mut acc = [0i32; OUT];
        self.0.accumulate(x, &mut acc);
        for ((y, a), rq) in y.iter_mut().zip(acc.iter()).zip(self.0.requants()) {
            *y = rq.apply_sat(*a);
        }
    }

    fn macs(&self) -> usize {
        Dense::<IN, OUT>::MACS
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn check(acc: i32, mult: i32, shift: u8, offset: i32) {
        let rq = Requant {
            mult,
            shift,
            offset,
        };
        let want = rq.apply(acc).clamp(i32::MIN as i64, i32::MAX as i64) as i32;
        assert_eq!(rq.apply_sat(acc), want, "{rq:?} acc={acc}");
    }

    #[test]
    fn apply_sat_at_the_edges() {
        for acc in [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX] {
            for mult in [0, 1, 1 << 30, i32::MAX, -1, i32::MIN] {
                for shift in [0, 1, 31, 32, 33, 34, 61, 62, 63, 255] {
                    for offset in [i32::MIN, -1, 0, 1, i32::MAX] {
                        check(acc, mult, shift, offset);
                    }
                }
            }
        }
    }

    proptest! {
        #[test]
        fn apply_sat_is_apply_saturated(acc in any::<i32>(), mult in any::<i32>(), shift in any::<u8>(), offset in any::<i32>()) {
            check(acc, mult, shift, offset);
        }

        #[test]
        fn apply_sat_on_trained_ranges(acc in -(1i32 << 28)..(1 << 28), mult in (1i32 << 30)..i32::MAX, shift in 30u8..46, offset in -100_000i32..100_000) {
            check(acc, mult, shift, offset);
        }
    }
}
