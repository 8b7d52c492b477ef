//! Fixed-size quantized MLP layers: int8 weights, int16 activations, int32 accumulation. How the
//! weights are stored (int16 halves in kernel order by default) is the business of [`kernel`].
//!
//! Shapes are const generics, so a weight table of the wrong shape does not compile, and a network is
//! a nested [`Chain`] of layers whose widths must line up at compile time.
//!
//! Number format (symmetric, no zero points): a layer's real input is `x_q * s_x`, its weights are
//! `w_q[o][i] * s_w[o]` (one scale per output channel), and its bias is pre-scaled to the accumulator,
//! `b_q[o] = round(b[o] / (s_x * s_w[o]))`. The int32 accumulator `acc[o] = b_q[o] + Σ x_q[i] w_q[o][i]`
//! is requantized to the next layer's scale with an integer multiplier and a right shift
//! ([`Requant`]). Hidden layers saturate to int16 after ReLU; output layers keep int32.
//!
//! Overflow cannot happen: `|x_q| ≤ 32767`, `|w_q| ≤ 127` and `IN ≤` [`MAX_IN`], and every bias is
//! checked against the remaining head-room when the layer is built (at compile time for the
//! generated statics). All three kernels still use wrapping adds, so they agree bit for bit in all cases.

mod dense;
#[cfg(any(test, feature = "float-ref"))]
pub mod float;
pub mod kernel;

pub use dense::{Dense, Hidden, Output, Requant};

/// Largest layer input width: `MAX_IN * 32767 * 127` stays below `i32::MAX` with room for a bias.
pub const MAX_IN: usize = 512;

/// Largest magnitude of the worst-case sum of products for `inputs` inputs.
pub const fn max_products(inputs: usize) -> i64 {
    // A bound: saturating keeps it an upper bound for any width (exact up to far beyond MAX_IN).
    (inputs as i64).saturating_mul(32767 * 127)
}

/// A layer (or a chain of layers) mapping `IN` int16 activations to `OUT` outputs.
pub trait Layer<const IN: usize, const OUT: usize> {
    /// int16 for hidden layers, int32 for output layers.
    type Out: Copy + Default;
    fn forward(&self, x: &[i16; IN], y: &mut [Self::Out; OUT]);
    /// Multiply-accumulates per forward pass (for benchmarks: instructions per MAC).
    fn macs(&self) -> usize;
}

/// int16 activations on a word boundary, so that the int16 kernel loads them in pairs without
/// copying them first: the input of a network and the activations between two layers.
#[repr(C, align(4))]
pub(crate) struct Aligned<const N: usize>(pub [i16; N]);

/// Two layers in sequence, with the intermediate width `MID` checked by the type system. A chain
/// is a layer only if the first layer's outputs are the second one's inputs:
/// ```
/// use estimator_core::nn::{Chain, Dense, Hidden, Layer, Output, Requant};
/// let net = Chain::<_, _, 3>(
///     Hidden(Dense::<2, 3>::new([[1, 2], [3, 4], [5, 6]], [0; 3], [Requant::ONE; 3])),
///     Output(Dense::<3, 1>::new([[1, 1, 1]], [0], [Requant::ONE])),
/// );
/// let mut y = [0i32; 1];
/// net.forward(&[1, 2], &mut y);
/// assert_eq!(y, [5 + 11 + 17]);
/// ```
/// Dense layers with mismatched shapes (three outputs into four inputs) are not a layer:
/// ```compile_fail,E0599
/// use estimator_core::nn::{Chain, Dense, Hidden, Layer, Output, Requant};
/// let net = Chain::<_, _, 3>(
///     Hidden(Dense::<2, 3>::new([[1, 2], [3, 4], [5, 6]], [0; 3], [Requant::ONE; 3])),
///     Output(Dense::<4, 1>::new([[1, 1, 1, 1]], [0], [Requant::ONE])),
/// );
/// let mut y = [0i32; 1];
/// net.forward(&[1, 2], &mut y);
/// ```
pub struct Chain<A, B, const MID: usize>(pub A, pub B);

impl<A, B, const IN: usize, const MID: usize, const OUT: usize> Layer<IN, OUT> for Chain<A, B, MID>
where
    A: Layer<IN, MID, Out = i16>,
    B: Layer<MID, OUT>,
{
    type Out = B::Out;

    #[inline]
    fn forward(&self, x: &[i16; IN], y: &mut [Self::Out; OUT]) {
        let mut mid = Aligned([0i16; MID]);
        self.0.forward(x, &mut mid.0);
        self.1.forward(&mid.0, y);
    }

    fn macs(&self) -> usize {
        self.0.macs().saturating_add(self.1.macs())
    }
}
