//! Int16 weight storage (the default) and its kernel: every int8 weight is widened to an int16 half
//! when the layer is built (at compile time for the generated statics) and stored in the order the
//! kernel reads it, so that the inner loop is loads and `SMLAD`s only.
//!
//! # Layout
//! Output rows are taken in blocks of four (then one block of two and a single row for the `OUT % 4`
//! left over). Within a block of `R` rows, for each input pair `k` (inputs `2k`, `2k+1`) the block holds
//! `R` words, one per row: `(w[r][2k], w[r][2k+1])` as (low, high) halves. An odd last input follows as
//! `R` halves, one per row. A block of `R` rows therefore takes exactly `R * IN` halves, and the whole
//! table exactly the `OUT * IN` halves of a `[[i16; IN]; OUT]`, which is how it is stored (aligned to 4
//! bytes). Every block starts after an even number of rows, so on a word boundary.
//!
//! # Inner loop on the Cortex-M4 (four rows, two input pairs)
//! ```text
//! ldrd  r12, r10, [px], #8      @ input pairs (x0,x1) and (x2,x3)
//! ldm   pw!, {r0-r3}            @ the four rows' weight pairs for (x0,x1)
//! smlad r4, r0, r12, r4         @ row 0 += w00·x0 + w01·x1
//! smlad r5, r1, r12, r5         @ row 1
//! smlad r8, r2, r12, r8         @ row 2
//! smlad r9, r3, r12, r9         @ row 3
//! ldm   pw!, {r0-r3}            @ the four rows' weight pairs for (x2,x3)
//! smlad r4, r0, r10, r4         @ ... four more SMLADs
//! ```
//! Eleven instructions per sixteen MACs (0.69); the loop runs four of these per test (47 instructions
//! per 64 MACs, 0.73). That takes twelve registers, all that inline assembly may use on Thumb (r6 and
//! r7 belong to LLVM), so the loop's end address, and the pointers of the loop over blocks, live on
//! the stack. The input pairs left over (`IN / 2 % 8` of them) are unrolled at compile time, as is the
//! odd last input (`SMLABB`/`SMLATB`), and one block of assembly runs all the blocks of four rows of a
//! layer. Measured on QEMU: 0.74 instructions per MAC on a 512→256 layer, 0.80 on 64→32, ≈1.0 on
//! 13→32 (see `docs/results/wcet.md`).
//!
//! On `target_arch = "arm"` the loops are inline assembly; elsewhere (and on Arm, should a slice ever
//! be misaligned) the same layout is read by plain Rust with an exact `SMLAD` emulation, which the
//! tests compare with [`super::accumulate_portable`].

use super::{pack, smlad};
use crate::nn::Aligned;

/// Output rows per block of the main loop.
const BLOCK: usize = 4;

/// Rows of the block that starts with `left` rows still to place: 4, then 2, then 1.
const fn block_rows(left: usize) -> usize {
    if left >= BLOCK {
        BLOCK
    } else if left >= 2 {
        2
    } else {
        1
    }
}

/// The weights of a layer as int16 halves in kernel order (see the module docs). Built from the int8
/// table by [`Int16Weights::new`]; the `[[i16; IN]; OUT]` shape gives the size, not the meaning.
#[repr(C, align(4))]
pub struct Int16Weights<const IN: usize, const OUT: usize> {
    halves: [[i16; IN]; OUT],
}

impl<const IN: usize, const OUT: usize> Int16Weights<IN, OUT> {
    /// Rows in the blocks of four, and their halves.
    const FULL_ROWS: usize = OUT / BLOCK * BLOCK;
    const FULL_HALVES: usize = Self::FULL_ROWS * IN;
    /// Rows in the block of two among the `OUT % 4` left (0 or 2), and their halves.
    const TWO_ROWS: usize = if OUT % BLOCK >= 2 { 2 } else { 0 };
    const TWO_HALVES: usize = Self::TWO_ROWS * IN;

    /// Widens and re-orders `w` (row `o` = the weights of output `o`, in input order).
    // Indexing and arithmetic here run in const evaluation for the generated statics: out of bounds
    // or an overflow is a compile error there.
    #[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)]
    pub const fn new(w: &[[i8; IN]; OUT]) -> Self {
        let mut halves = [[0i16; IN]; OUT];
        let even = IN / 2 * 2;
        let mut n = 0; // next half, in storage order
        let mut r0 = 0;
        while r0 < OUT {
            let rows = block_rows(OUT - r0);
            let mut i = 0;
            while i < even {
                let mut r = r0;
                while r < r0 + rows {
                    halves[n / IN][n % IN] = w[r][i] as i16;
                    halves[(n + 1) / IN][(n + 1) % IN] = w[r][i + 1] as i16;
                    n += 2;
                    r += 1;
                }
                i += 2;
            }
            if even < IN {
                let mut r = r0;
                while r < r0 + rows {
                    halves[n / IN][n % IN] = w[r][even] as i16;
                    n += 1;
                    r += 1;
                }
            }
            r0 += rows;
        }
        Int16Weights { halves }
    }

    /// Index in storage order of weight `(o, i)`, both in range (the layout test reads it back).
    #[cfg(test)]
    const fn position(o: usize, i: usize) -> usize {
        let full = OUT / BLOCK * BLOCK;
        let r0 = if o < full {
            o / BLOCK * BLOCK
        } else if OUT - full >= 2 && o < full + 2 {
            full
        } else {
            o
        };
        let rows = block_rows(OUT - r0);
        let even = IN / 2 * 2;
        if i < even {
            r0 * IN + i / 2 * 2 * rows + 2 * (o - r0) + i % 2
        } else {
            r0 * IN + even * rows + (o - r0)
        }
    }

    /// Weight `(o, i)` as exported, `None` out of range.
    #[cfg(test)]
    pub fn get(&self, o: usize, i: usize) -> Option<i8> {
        if o >= OUT || i >= IN {
            return None;
        }
        let h = self.halves.as_flattened().get(Self::position(o, i))?;
        Some(*h as i8)
    }

    /// `acc[o] = bias[o] + Σ_i x[i] w[o][i]`.
    #[inline]
    pub fn accumulate(&self, bias: &[i32; OUT], x: &[i16; IN], acc: &mut [i32; OUT]) {
        accumulate_wide(self, bias, x, acc);
    }
}

/// The int16 kernel (see the module docs).
#[inline(never)]
pub fn accumulate_wide<const IN: usize, const OUT: usize>(
    w: &Int16Weights<IN, OUT>,
    bias: &[i32; OUT],
    x: &[i16; IN],
    acc: &mut [i32; OUT],
) {
    // The Arm loops load input pairs as words. The estimator's inputs and activations are
    // `nn::Aligned`; another caller's unaligned input is copied.
    let copy;
    let x = if (x.as_ptr() as usize).is_multiple_of(4) {
        x
    } else {
        copy = Aligned(*x);
        &copy.0
    };
    let flat = w.halves.as_flattened();
    let (Some((w4, w_rest)), Some((b4, b_rest)), Some((a4, a_rest))) = (
        flat.split_at_checked(Int16Weights::<IN, OUT>::FULL_HALVES),
        bias.split_at_checked(Int16Weights::<IN, OUT>::FULL_ROWS),
        acc.split_at_mut_checked(Int16Weights::<IN, OUT>::FULL_ROWS),
    ) else {
        return;
    };
    blocks4(w4, x, b4, a4);
    // The `OUT % 4` rows left: a block of two, then a single row.
    if let (Some((w2, w1)), Some((b2, b1)), Some((a2, a1))) = (
        w_rest.split_at_checked(Int16Weights::<IN, OUT>::TWO_HALVES),
        b_rest.split_at_checked(Int16Weights::<IN, OUT>::TWO_ROWS),
        a_rest.split_at_mut_checked(Int16Weights::<IN, OUT>::TWO_ROWS),
    ) {
        rows(w2, x, b2, a2);
        rows(w1, x, b1, a1);
    }
}

/// All the blocks of four rows: `acc = bias + w · x`, `w` being their `acc.len() * IN` halves.
#[inline(always)]
fn blocks4<const IN: usize>(w: &[i16], x: &[i16; IN], bias: &[i32], acc: &mut [i32]) {
    #[cfg(target_arch = "arm")]
    if arm::blocks4(w, x, bias, acc) {
        return;
    }
    let blocks = w.chunks_exact(const { BLOCK * IN });
    for ((blk, b), a) in blocks
        .zip(bias.chunks_exact(BLOCK))
        .zip(acc.chunks_exact_mut(BLOCK))
    {
        rows(blk, x, b, a);
    }
}

/// A block of `bias.len()` rows (0, 1, 2 or 4): `acc = bias + w · x`, `blk` being the block's halves.
#[inline(always)]
fn rows(blk: &[i16], x: &[i16], bias: &[i32], acc: &mut [i32]) {
    let mut s = [0i32; BLOCK];
    let s = match s.get_mut(..bias.len()) {
        Some(s) => s,
        None => return,
    };
    for (sj, b) in s.iter_mut().zip(bias) {
        *sj = *b;
    }
    let (pairs, last) = x.as_chunks::<2>();
    let pairs = pairs.as_flattened();
    // At most 4 × MAX_IN; were it to saturate, the checked split would fail rather than cut wrongly.
    let Some((w_pairs, w_last)) = blk.split_at_checked(s.len().saturating_mul(pairs.len())) else {
        return;
    };
    dot(w_pairs, pairs, s);
    if let Some(xl) = last.first() {
        for (sj, wj) in s.iter_mut().zip(w_last) {
            // An int16 product is exact in i32; the sum wraps by definition (as SMLAD does).
            *sj = sj.wrapping_add(i32::from(*wj).wrapping_mul(i32::from(*xl)));
        }
    }
    for (a, sj) in acc.iter_mut().zip(s.iter()) {
        *a = *sj;
    }
}

/// `s[r] += Σ_k smlad(w_k,r, x_k)`: for each input pair `x_k` of `x`, `w` holds one weight pair per row.
#[inline(always)]
fn dot(w: &[i16], x: &[i16], s: &mut [i32]) {
    #[cfg(target_arch = "arm")]
    if arm::dot(w, x, s) {
        return;
    }
    dot_emulated(w, x, s);
}

/// [`dot`] in plain Rust.
#[inline(always)]
fn dot_emulated(w: &[i16], x: &[i16], s: &mut [i32]) {
    if s.is_empty() {
        return;
    }
    // `s` is not empty, so the chunk length is at least 2.
    for (wk, xk) in w
        .chunks_exact(s.len().saturating_mul(2))
        .zip(x.chunks_exact(2))
    {
        let xv = pair(xk);
        for (sr, wr) in s.iter_mut().zip(wk.chunks_exact(2)) {
            *sr = smlad(pair(wr), xv, *sr);
        }
    }
}

/// The two int16 of `h` packed into a word (0 unless `h` holds exactly two).
#[inline(always)]
fn pair(h: &[i16]) -> u32 {
    match h {
        [lo, hi] => pack(*lo, *hi),
        _ => 0,
    }
}

#[cfg(target_arch = "arm")]
#[allow(unsafe_code)]
mod arm {
    use core::arch::asm;

    // One input pair (r12) for four rows: weights in r0-r3, accumulators in r4, r5, r8, r9.
    macro_rules! single4 {
        () => {
            "ldr r12, [{px}], #4\n\
             ldm {pw}!, {{r0, r1, r2, r3}}\n\
             smlad r4, r0, r12, r4\n\
             smlad r5, r1, r12, r5\n\
             smlad r8, r2, r12, r8\n\
             smlad r9, r3, r12, r9\n"
        };
    }
    // Two input pairs (r12, r10) for four rows: one LDRD of inputs per 16 MACs.
    macro_rules! double4 {
        () => {
            "ldrd r12, r10, [{px}], #8\n\
             ldm {pw}!, {{r0, r1, r2, r3}}\n\
             smlad r4, r0, r12, r4\n\
             smlad r5, r1, r12, r5\n\
             smlad r8, r2, r12, r8\n\
             smlad r9, r3, r12, r9\n\
             ldm {pw}!, {{r0, r1, r2, r3}}\n\
             smlad r4, r0, r10, r4\n\
             smlad r5, r1, r10, r5\n\
             smlad r8, r2, r10, r8\n\
             smlad r9, r3, r10, r9\n"
        };
    }
    // Four input pairs for one row: inputs in r0-r3, weights in r4, r5, r8, r9.
    macro_rules! step1x4 {
        () => {
            "ldm {px}!, {{r0, r1, r2, r3}}\n\
             ldm {pw}!, {{r4, r5, r8, r9}}\n\
             smlad {s}, r0, r4, {s}\n\
             smlad {s}, r1, r5, {s}\n\
             smlad {s}, r2, r8, {s}\n\
             smlad {s}, r3, r9, {s}\n"
        };
    }

    /// [`super::blocks4`] in one block of assembly. Per block of four rows: bias load, the input
    /// pairs not looped over (an odd one, then pairs of pairs), the main loop (eight pairs per loop
    /// test), the odd last input and the store of the four sums, all unrolled or counted at compile
    /// time from `IN`. Returns `false` (nothing done) for no blocks, slices of mismatched lengths or
    /// misaligned ones, which never happen with [`super::Int16Weights`] (aligned, blocks on word
    /// boundaries) and a word-aligned input.
    #[inline(always)]
    pub fn blocks4<const IN: usize>(
        w: &[i16],
        x: &[i16; IN],
        bias: &[i32],
        acc: &mut [i32],
    ) -> bool {
        // `n` blocks of four rows: `acc.len() * IN` halves of `w` (checked, not wrapped: the
        // assembly's memory safety rests on these lengths).
        let n = acc.len() / 4;
        let Some(halves) = acc.len().checked_mul(IN) else {
            return false;
        };
        if n == 0
            || !acc.len().is_multiple_of(4)
            || bias.len() != acc.len()
            || w.len() < halves
            || !(w.as_ptr() as usize | x.as_ptr() as usize).is_multiple_of(4)
        {
            return false;
        }
        // SAFETY: for each of the `n` blocks, reads four words of `bias`, the `IN` halves of `x` (px:
        // `IN / 2` words, then the odd last half) and the block's `4 * IN` halves of `w` (pw: four words
        // per input pair, then two words for an odd last input; the blocks follow each other), and
        // writes four words of `acc`: `n` blocks in all, so within the four slices (lengths checked
        // above), all word-aligned as LDM, STM and LDRD require (checked above; `4 * IN` halves are
        // a whole number of words). The pointers to `acc`, `bias` and `x` and the end of `acc` live in a
        // 16-byte frame pushed on the stack (there is no free register), as does, during the main loop,
        // its end address (`px` plus at most 1024 bytes with `IN <= MAX_IN`, within ADDW's range); both
        // are popped before the end. Writes only the named registers, `acc` and those stack words; the
        // loop tests change the flags (not preserved).
        unsafe {
            asm!(
                "push {{r1, r2, r3, r12}}", // [sp]: acc, [sp+4]: bias, [sp+8]: x, [sp+12]: acc end
                "3:",
                "ldr r0, [sp, #4]",
                "ldm r0!, {{r4, r5, r8, r9}}",
                "str r0, [sp, #4]",
                "ldr {px}, [sp, #8]",
                ".if {single}",
                single4!(),
                ".endif",
                ".rept {doubles}",
                double4!(),
                ".endr",
                ".if {looped}",
                "addw r0, {px}, #{looped_bytes}",
                "push {{r0}}",
                "2:",
                double4!(),
                double4!(),
                double4!(),
                double4!(),
                "ldr r0, [sp]",
                "cmp {px}, r0",
                "bne 2b",
                "add sp, #4",
                ".endif",
                ".if {odd}",
                "ldrh r12, [{px}]",
                "ldm {pw}!, {{r0, r1}}",
                "smlabb r4, r0, r12, r4",
                "smlatb r5, r0, r12, r5",
                "smlabb r8, r1, r12, r8",
                "smlatb r9, r1, r12, r9",
                ".endif",
                "ldr r0, [sp]",
                "stm r0!, {{r4, r5, r8, r9}}",
                "str r0, [sp]",
                "ldr r1, [sp, #12]",
                "cmp r0, r1",
                "bne 3b",
                "add sp, #16",
                single = const IN / 2 % 2,
                doubles = const IN / 2 % 8 / 2,
                looped = const (IN / 16 > 0) as usize,
                looped_bytes = const IN / 16 * 32,
                odd = const IN % 2,
                px = out(reg) _,
                pw = inout(reg) w.as_ptr() => _,
                inout("r1") acc.as_mut_ptr() => _,
                inout("r2") bias.as_ptr() => _,
                inout("r3") x.as_ptr() => _,
                inout("r12") acc.as_mut_ptr_range().end => _,
                out("r0") _, out("r4") _, out("r5") _, out("r8") _, out("r9") _, out("r10") _,
                options(),
            );
        }
        true
    }

    /// [`super::dot`] for blocks of 2 or 1 rows in inline assembly. Returns `false` (nothing done)
    /// for other block sizes, short weights or misaligned slices, which never happen with
    /// [`super::Int16Weights`] and a word-aligned input.
    #[inline(always)]
    pub fn dot(w: &[i16], x: &[i16], s: &mut [i32]) -> bool {
        // The input pairs: `words` words, ending at `pairs_end`.
        let (pairs, _) = x.as_chunks::<2>();
        let (words, pairs_end) = (pairs.len(), pairs.as_flattened().as_ptr_range().end);
        if words == 0 {
            return true;
        }
        // One weight word per row and input pair (checked, not wrapped: the assembly's memory
        // safety rests on this length).
        let need = s.len().checked_mul(pairs.as_flattened().len());
        if !(w.as_ptr() as usize | x.as_ptr() as usize).is_multiple_of(4)
            || need.is_none_or(|need| w.len() < need)
        {
            return false;
        }
        let mut px = x.as_ptr();
        let mut pw = w.as_ptr();
        match s {
            [s0, s1] => {
                let end = pairs_end;
                // SAFETY: per iteration one input word at `px` and two weight words at `pw`, both
                // advancing, `words` (> 0) iterations: within `x` and the `2 * words` words of `w`,
                // word-aligned as LDRD requires (checked above).
                unsafe {
                    asm!("2:",
                        "ldr r12, [{px}], #4",
                        "ldrd r0, r1, [{pw}], #8",
                        "smlad {s0}, r0, r12, {s0}",
                        "smlad {s1}, r1, r12, {s1}",
                        "cmp {px}, {end}", "bne 2b",
                        px = inout(reg) px => _, pw = inout(reg) pw => _, end = in(reg) end,
                        s0 = inout(reg) *s0, s1 = inout(reg) *s1,
                        out("r0") _, out("r1") _, out("r12") _,
                        options(nostack, readonly));
                }
                true
            }
            [s0] => {
                let mut a = *s0;
                for _ in 0..words % 4 {
                    // SAFETY: one input word and one weight word, within `x` and `w` (checked above).
                    unsafe {
                        asm!("ldr r0, [{px}], #4",
                            "ldr r4, [{pw}], #4",
                            "smlad {s}, r0, r4, {s}",
                            px = inout(reg) px, pw = inout(reg) pw, s = inout(reg) a,
                            out("r0") _, out("r4") _,
                            options(nostack, readonly, preserves_flags));
                    }
                }
                let n = words / 4;
                if n > 0 {
                    // After the single words above, the `4 × n` words left end with the pairs.
                    let end = pairs_end;
                    // SAFETY: four input and four weight words per iteration, `n` iterations: the
                    // rest of `x`'s `words` words and of `w`'s (checked above), word-aligned for LDM.
                    unsafe {
                        asm!("2:", step1x4!(), "cmp {px}, {end}", "bne 2b",
                            px = inout(reg) px => _, pw = inout(reg) pw => _, end = in(reg) end, s = inout(reg) a,
                            out("r0") _, out("r1") _, out("r2") _, out("r3") _,
                            out("r4") _, out("r5") _, out("r8") _, out("r9") _,
                            options(nostack, readonly));
                    }
                }
                *s0 = a;
                true
            }
            _ => false,
        }
    }
}
