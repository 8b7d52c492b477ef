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

    #[inline(always)]
    pub fn apply(self, acc: i32) -> i64 {
        let shift = (self.shift as u32).clamp(1, 62);
        let prod = acc as i64 * self.mult as i64 + (1i64 << (shift - 1));
        (prod >> shift) + self.offset as i64
    }
}

/// Weights, bias and requantization of one fully connected layer.
pub struct Dense<const IN: usize, const OUT: usize> {
    /// Row `o` holds the int8 weights of output `o`, in input order. Values are in -127..=127.
    pub weights: [[i8; IN]; OUT],
    /// Bias in accumulator units.
    pub bias: [i32; OUT],
    pub requant: [Requant; OUT],
}

impl<const IN: usize, const OUT: usize> Dense<IN, OUT> {
    /// Builds a layer, refusing (at compile time when used in a `static`) shapes and values that could
    /// overflow the int32 accumulator or break the symmetric int8 range.
    // Indexing here runs in const evaluation for the generated statics: out of bounds is a compile error.
    #[allow(clippy::indexing_slicing)]
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
            weights,
            bias,
            requant,
        }
    }

    /// Int32 accumulators with the bias, using the fastest kernel for this target.
    #[inline]
    pub fn accumulate(&self, x: &[i16; IN], acc: &mut [i32; OUT]) {
        kernel::accumulate(&self.weights, &self.bias, x, acc);
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
        for ((y, a), rq) in y.iter_mut().zip(acc.iter()).zip(self.0.requant.iter()) {
            *y = rq.apply(*a).clamp(0, i16::MAX as i64) as i16;
        }
    }

    fn macs(&self) -> usize {
        IN * OUT
    }
}

impl<const IN: usize, const OUT: usize> Layer<IN, OUT> for Output<IN, OUT> {
    type Out = i32;

    #[inline]
    fn forward(&self, x: &[i16; IN], y: &mut [i32; OUT]) {
        let mut acc = [0i32; OUT];
        self.0.accumulate(x, &mut acc);
        for ((y, a), rq) in y.iter_mut().zip(acc.iter()).zip(self.0.requant.iter()) {
            *y = rq.apply(*a).clamp(i32::MIN as i64, i32::MAX as i64) as i32;
        }
    }

    fn macs(&self) -> usize {
        IN * OUT
    }
}
