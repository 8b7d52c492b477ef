//! The two dense kernels. Both compute `acc[o] = bias[o] + Σ_i x[i] * w[o][i]` with wrapping int32 adds.
//!
//! * [`accumulate_portable`]: plain Rust, one MAC at a time.
//! * [`accumulate_dsp`]: the Cortex-M4 DSP formulation. The input is packed once per layer into int16
//!   pairs in the order `(x0,x2) (x1,x3)` per group of four, so that one 32-bit load of four int8
//!   weights `w0 w1 w2 w3` feeds two `SXTB16` (which widen `(w0,w2)` and, rotated by 8, `(w1,w3)`) and two
//!   `SMLAD` (two MACs each), with no weight re-ordering in flash. Two output rows share each input load.
//!   On `target_arch = "arm"` the three primitives are the real instructions; elsewhere they are exact
//!   emulations, so the same kernel is property-tested on the host against the portable one.
//!
//! [`accumulate`] picks the DSP kernel on Arm and the portable kernel elsewhere.

use super::MAX_IN;

/// The kernel this build uses.
#[inline]
pub fn accumulate<const IN: usize, const OUT: usize>(
    w: &[[i8; IN]; OUT],
    bias: &[i32; OUT],
    x: &[i16; IN],
    acc: &mut [i32; OUT],
) {
    #[cfg(target_arch = "arm")]
    accumulate_dsp(w, bias, x, acc);
    #[cfg(not(target_arch = "arm"))]
    accumulate_portable(w, bias, x, acc);
}

/// Reference kernel: one multiply-accumulate per weight.
pub fn accumulate_portable<const IN: usize, const OUT: usize>(
    w: &[[i8; IN]; OUT],
    bias: &[i32; OUT],
    x: &[i16; IN],
    acc: &mut [i32; OUT],
) {
    for ((row, b), a) in w.iter().zip(bias.iter()).zip(acc.iter_mut()) {
        let mut s = *b;
        for (xi, wi) in x.iter().zip(row.iter()) {
            s = s.wrapping_add(*xi as i32 * *wi as i32);
        }
        *a = s;
    }
}

/// DSP kernel (see the module docs). `IN` is at most [`MAX_IN`] (checked when the layer is built).
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
    let groups = IN / 4;
    let packed = packed.get(..groups * 2).unwrap_or(&[]);
    let tail_x = x.get(groups * 4..).unwrap_or(&[]);

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
            *a0 = tail(r0, tail_x, groups, s0);
            *a1 = tail(r1, tail_x, groups, s1);
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
        *a = tail(r, tail_x, groups, s);
    }
}

/// The last `IN % 4` products, one at a time.
#[inline(always)]
fn tail(row: &[i8], tail_x: &[i16], groups: usize, mut s: i32) -> i32 {
    for (xi, wi) in tail_x.iter().zip(row.get(groups * 4..).unwrap_or(&[])) {
        s = s.wrapping_add(*xi as i32 * *wi as i32);
    }
    s
}

#[inline(always)]
fn pack(lo: i16, hi: i16) -> u32 {
    (lo as u16 as u32) | ((hi as u16 as u32) << 16)
}

#[inline(always)]
fn word(b: [i8; 4]) -> u32 {
    u32::from_le_bytes([b[0] as u8, b[1] as u8, b[2] as u8, b[3] as u8])
}

/// `SMLAD acc, a, b`: `acc + a.lo*b.lo + a.hi*b.hi` (signed 16-bit halves, wrapping).
#[cfg(not(target_arch = "arm"))]
#[inline(always)]
pub fn smlad(a: u32, b: u32, acc: i32) -> i32 {
    let lo = (a as u16 as i16 as i32) * (b as u16 as i16 as i32);
    let hi = ((a >> 16) as u16 as i16 as i32) * ((b >> 16) as u16 as i16 as i32);
    acc.wrapping_add(lo).wrapping_add(hi)
}

/// `SXTB16 r, x`: sign-extend bytes 0 and 2 into the two halfwords.
#[cfg(not(target_arch = "arm"))]
#[inline(always)]
pub fn sxtb16(x: u32) -> u32 {
    let lo = x as u8 as i8 as i16 as u16 as u32;
    let hi = (x >> 16) as u8 as i8 as i16 as u16 as u32;
    lo | (hi << 16)
}

/// `SXTB16 r, x, ROR #8`: sign-extend bytes 1 and 3 into the two halfwords.
#[cfg(not(target_arch = "arm"))]
#[inline(always)]
pub fn sxtb16_ror8(x: u32) -> u32 {
    sxtb16(x.rotate_right(8))
}

#[cfg(target_arch = "arm")]
#[allow(unsafe_code)]
mod arm {
    use core::arch::asm;

    #[inline(always)]
    pub fn smlad(a: u32, b: u32, acc: i32) -> i32 {
        let r: i32;
        // SAFETY: register-only arithmetic instruction of ARMv7E-M (DSP extension); no memory access.
        unsafe {
            asm!("smlad {r}, {a}, {b}, {c}", r = lateout(reg) r, a = in(reg) a, b = in(reg) b, c = in(reg) acc,
                 options(pure, nomem, nostack, preserves_flags));
        }
        r
    }

    #[inline(always)]
    pub fn sxtb16(x: u32) -> u32 {
        let r: u32;
        // SAFETY: register-only instruction of ARMv7E-M (DSP extension).
        unsafe {
            asm!("sxtb16 {r}, {x}", r = lateout(reg) r, x = in(reg) x, options(pure, nomem, nostack, preserves_flags));
        }
        r
    }

    #[inline(always)]
    pub fn sxtb16_ror8(x: u32) -> u32 {
        let r: u32;
        // SAFETY: register-only instruction of ARMv7E-M (DSP extension).
        unsafe {
            asm!("sxtb16 {r}, {x}, ror #8", r = lateout(reg) r, x = in(reg) x,
                 options(pure, nomem, nostack, preserves_flags));
        }
        r
    }
}
#[cfg(target_arch = "arm")]
pub use arm::{smlad, sxtb16, sxtb16_ror8};

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn primitives_match_their_definition() {
        assert_eq!(sxtb16(0x807F_FF01), 0x007F_0001);
        assert_eq!(sxtb16(0x00FF_00FE), 0xFFFF_FFFE);
        assert_eq!(sxtb16_ror8(0x7F00_8000), 0x007F_FF80);
        assert_eq!(smlad(pack(-3, 4), pack(5, -6), 100), 100 - 15 - 24);
        assert_eq!(
            smlad(pack(i16::MIN, 0), pack(i16::MIN, 0), i32::MAX),
            i32::MAX.wrapping_add(1 << 30)
        );
    }

    fn check<const IN: usize, const OUT: usize>(seed: u64) {
        let mut s = seed | 1;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut w = [[0i8; IN]; OUT];
        for row in w.iter_mut() {
            for v in row.iter_mut() {
                *v = (next() % 255) as i16 as i8; // full int8 range incl. -128: kernels must agree anyway
            }
        }
        let bias: [i32; OUT] = core::array::from_fn(|_| next() as i32);
        let x: [i16; IN] = core::array::from_fn(|_| next() as i16);
        let (mut a, mut b) = ([0i32; OUT], [0i32; OUT]);
        accumulate_portable(&w, &bias, &x, &mut a);
        accumulate_dsp(&w, &bias, &x, &mut b);
        assert_eq!(a, b, "IN={IN} OUT={OUT} seed={seed}");
    }

    proptest! {
        #[test]
        fn dsp_equals_portable_on_random_values(seed in any::<u64>()) {
            check::<1, 1>(seed);
            check::<3, 2>(seed);
            check::<4, 1>(seed);
            check::<5, 3>(seed);
            check::<7, 7>(seed);
            check::<10, 32>(seed);
            check::<11, 9>(seed);
            check::<33, 16>(seed);
            check::<64, 33>(seed);
            check::<129, 5>(seed);
            check::<512, 3>(seed);
        }
    }
}
