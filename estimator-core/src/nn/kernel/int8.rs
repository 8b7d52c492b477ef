//! Int8 weight storage (feature `int8-weights`): half the flash of [`super::Int16Weights`], and the
//! `SXTB16` kernel, which needs about 2.0 instructions per MAC on the Cortex-M4.
//!
//! The input is packed once per call into int16 pairs in the order `(x0,x2) (x1,x3)` per group of four,
//! so that one 32-bit load of four int8 weights `w0 w1 w2 w3` feeds two `SXTB16` (which widen `(w0,w2)`
//! and, rotated by 8, `(w1,w3)`) and two `SMLAD` (two MACs each), with no weight re-ordering in flash.
//! Two output rows share each input load. The widening costs one instruction per two MACs, on top of
//! the `SMLAD`, which is why this kernel cannot reach one instruction per MAC.

use super::{MAX_IN, pack, smlad, sxtb16, sxtb16_ror8};

/// The int8 weights exactly as exported: row `o` holds the weights of output `o`, in input order.
pub struct Int8Weights<const IN: usize, const OUT: usize>(pub [[i8; IN]; OUT]);

impl<const IN: usize, const OUT: usize> Int8Weights<IN, OUT> {
    pub const fn new(w: &[[i8; IN]; OUT]) -> Self {
        Int8Weights(*w)
    }

    /// `acc[o] = bias[o] + Σ_i x[i] w[o][i]`: the `SXTB16` kernel on Arm, the portable one elsewhere.
    #[inline]
    pub fn accumulate(&self, bias: &[i32; OUT], x: &[i16; IN], acc: &mut [i32; OUT]) {
        #[cfg(target_arch = "arm")]
        accumulate_dsp(&self.0, bias, x, acc);
        #[cfg(not(target_arch = "arm"))]
        super::accumulate_portable(&self.0, bias, x, acc);
    }
}

/// The `SXTB16` kernel (see the module docs). `IN` is at most [`MAX_IN`] (checked when the layer is built).
#[inline(never)]
pub fn accumulate_dsp<const IN: usize, const OUT: usize>(
    w: &[[i8; IN]; OUT],
    bias: &[i32; OUT],
    x: &[i16; IN],
    acc: &mut [i32; OUT],
) {
    // Packed pairs: for group g, packed[2g] = (x[4g], x[4g+2]) and packed[2g+1] = (x[4g+1], x[4g+3]).
    let mut packed = [0u32; MAX_IN / 2];
    for (p, q) in packed.chunks_exact_mut(2).zip(x.chunks_exact(4)) {
        if let ([p0, p1], [x0, x1, x2, x3]) = (p, q) {
            *p0 = pack(*x0, *x2);
            *p1 = pack(*x1, *x3);
        }
    }
    // Groups of four inputs, their packed words, and where the inputs left over start.
    let packed = packed.get(..const { IN / 4 * 2 }).unwrap_or(&[]);
    let tail_start = const { IN / 4 * 4 };
    let tail_x = x.get(tail_start..).unwrap_or(&[]);

    let mut rows = w.chunks_exact(2);
    let mut biases = bias.chunks_exact(2);
    let mut accs = acc.chunks_exact_mut(2);
    for ((pair, b), a) in (&mut rows).zip(&mut biases).zip(&mut accs) {
        if let ([r0, r1], [b0, b1], [a0, a1]) = (pair, b, a) {
            let (mut s0, mut s1) = (*b0, *b1);
            for ((w0, w1), xp) in r0
                .chunks_exact(4)
                .zip(r1.chunks_exact(4))
                .zip(packed.chunks_exact(2))
            {
                if let ([x02, x13], Ok(w0), Ok(w1)) =
                    (xp, <[i8; 4]>::try_from(w0), <[i8; 4]>::try_from(w1))
                {
                    let (w0, w1) = (word(w0), word(w1));
                    s0 = smlad(sxtb16(w0), *x02, s0);
                    s1 = smlad(sxtb16(w1), *x02, s1);
                    s0 = smlad(sxtb16_ror8(w0), *x13, s0);
                    s1 = smlad(sxtb16_ror8(w1), *x13, s1);
                }
            }
            *a0 = tail(r0, tail_x, tail_start, s0);
            *a1 = tail(r1, tail_x, tail_start, s1);
        }
    }
    // An odd last row.
    for ((r, b), a) in rows
        .remainder()
        .iter()
        .zip(biases.remainder())
        .zip(accs.into_remainder())
    {
        let mut s = *b;
        for (wq, xp) in r.chunks_exact(4).zip(packed.chunks_exact(2)) {
            if let ([x02, x13], Ok(wq)) = (xp, <[i8; 4]>::try_from(wq)) {
                let wq = word(wq);
                s = smlad(sxtb16(wq), *x02, s);
                s = smlad(sxtb16_ror8(wq), *x13, s);
            }
        }
        *a = tail(r, tail_x, tail_start, s);
    }
}

/// The last `IN % 4` products (inputs from `start` on), one at a time.
#[inline(always)]
fn tail(row: &[i8], tail_x: &[i16], start: usize, mut s: i32) -> i32 {
    for (xi, wi) in tail_x.iter().zip(row.get(start..).unwrap_or(&[])) {
        // |x × w| <= 2^15 × 2^7: the product is exact; the sum wraps by definition.
        s = s.wrapping_add(i32::from(*xi).wrapping_mul(i32::from(*wi)));
    }
    s
}

#[inline(always)]
fn word(b: [i8; 4]) -> u32 {
    u32::from_le_bytes([b[0] as u8, b[1] as u8, b[2] as u8, b[3] as u8])
}
