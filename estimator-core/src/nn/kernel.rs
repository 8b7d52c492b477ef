//! The dense kernels: `acc[o] = bias[o] + Σ_i x[i] * w[o][i]` with wrapping int32 adds, int8 weight
//! values (-127..=127), int16 activations.
//!
//! Two storage formats, chosen at build time; the generated weights files are the same for both (an
//! int8 table handed to the const fn `Dense::new`, which builds the stored form at compile time):
//!
//! * [`Int16Weights`] (default): each weight widened to an int16 half and re-ordered for the kernel,
//!   so that the Cortex-M4 inner loop is loads and `SMLAD`s only, four output rows sharing each input
//!   load (11 instructions per 16 MACs; measured 0.74 instructions per MAC on the paper-size network's
//!   large layers, 0.83 over the shipped medium model, 0.795 on its 64-input layers). Twice the flash
//!   of int8.
//! * [`Int8Weights`] (feature `int8-weights`): the int8 table as exported. Every pair of weights then
//!   needs an `SXTB16` besides its `SMLAD`, so this kernel cannot go below one instruction per MAC
//!   (measured ≈2.0). Half the flash, for models that would not fit otherwise.
//!
//! The figures and how they were measured: `docs/results/wcet.md`.
//!
//! [`accumulate_portable`] is the reference both are tested against (bit for bit, on random shapes and
//! values). On `target_arch = "arm"` the DSP primitives are the real instructions (inline assembly);
//! elsewhere they are exact emulations, so the Arm formulations run, and are tested, on the host too.
//! The int16 kernel's Arm loops are inline assembly of their own, checked against the same emulation on
//! QEMU (bit-for-bit HIL parity of the whole estimator, `hil-sim/tests/hil_qemu.rs`).

mod int16;
mod int8;

pub use int8::{Int8Weights, accumulate_dsp};
pub use int16::{Int16Weights, accumulate_wide};

use super::MAX_IN;

/// The weight storage of this build (see the module docs).
#[cfg(not(feature = "int8-weights"))]
pub type Weights<const IN: usize, const OUT: usize> = Int16Weights<IN, OUT>;
/// The weight storage of this build (see the module docs).
#[cfg(feature = "int8-weights")]
pub type Weights<const IN: usize, const OUT: usize> = Int8Weights<IN, OUT>;

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
            // |x × w| <= 2^15 × 2^7: the product is exact; the sum wraps by definition.
            s = s.wrapping_add(i32::from(*xi).wrapping_mul(i32::from(*wi)));
        }
        *a = s;
    }
}

/// Two int16 as the (low, high) halves of a word, as a little-endian load of them reads.
#[inline(always)]
pub fn pack(lo: i16, hi: i16) -> u32 {
    (lo as u16 as u32) | ((hi as u16 as u32) << 16)
}

/// `SMLAD acc, a, b`: `acc + a.lo*b.lo + a.hi*b.hi` (signed 16-bit halves, wrapping).
#[cfg(not(target_arch = "arm"))]
#[inline(always)]
pub fn smlad(a: u32, b: u32, acc: i32) -> i32 {
    // Products of two int16 are exact in i32 (|p| <= 2^30), as in SMLAD; the adds wrap, as in SMLAD.
    let lo = (a as u16 as i16 as i32).wrapping_mul(b as u16 as i16 as i32);
    let hi = ((a >> 16) as u16 as i16 as i32).wrapping_mul((b >> 16) as u16 as i16 as i32);
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
                *v = (next() % 256) as u8 as i8; // full int8 range incl. -128: kernels must agree anyway
            }
        }
        let bias: [i32; OUT] = core::array::from_fn(|_| next() as i32);
        let x: [i16; IN] = core::array::from_fn(|_| next() as i16);
        let mut want = [0i32; OUT];
        accumulate_portable(&w, &bias, &x, &mut want);

        let mut got = [0i32; OUT];
        accumulate_dsp(&w, &bias, &x, &mut got);
        assert_eq!(want, got, "int8 (SXTB16) IN={IN} OUT={OUT} seed={seed}");

        let wide = Int16Weights::new(&w);
        let mut got = [0i32; OUT];
        accumulate_wide(&wide, &bias, &x, &mut got);
        assert_eq!(want, got, "int16 IN={IN} OUT={OUT} seed={seed}");
        for (o, row) in w.iter().enumerate() {
            for (i, v) in row.iter().enumerate() {
                assert_eq!(
                    wide.get(o, i),
                    Some(*v),
                    "int16 layout ({o}, {i}) of {IN}x{OUT}"
                );
            }
        }
        assert_eq!(wide.get(OUT, 0), None);
        assert_eq!(wide.get(0, IN), None);

        let mut got = [0i32; OUT];
        Weights::new(&w).accumulate(&bias, &x, &mut got);
        assert_eq!(
            want, got,
            "this build's kernel IN={IN} OUT={OUT} seed={seed}"
        );
    }

    proptest! {
        #[test]
        fn kernels_equal_portable_on_random_values(seed in any::<u64>()) {
            check::<1, 1>(seed);
            check::<1, 6>(seed);
            check::<2, 2>(seed);
            check::<3, 2>(seed);
            check::<4, 1>(seed);
            check::<5, 3>(seed);
            check::<7, 7>(seed);
            check::<8, 5>(seed);
            check::<10, 32>(seed);
            check::<11, 9>(seed);
            check::<13, 4>(seed);
            check::<16, 1>(seed);
            check::<17, 11>(seed);
            check::<33, 16>(seed);
            check::<64, 33>(seed);
            check::<129, 5>(seed);
            check::<512, 3>(seed);
        }
    }

    #[test]
    fn extreme_values_wrap_alike() {
        let w = [[-128i8; 9]; 6];
        let x = [i16::MIN; 9];
        let bias = [i32::MAX; 6];
        let (mut want, mut got) = ([0i32; 6], [0i32; 6]);
        accumulate_portable(&w, &bias, &x, &mut want);
        accumulate_wide(&Int16Weights::new(&w), &bias, &x, &mut got);
        assert_eq!(want, got);
    }
}
