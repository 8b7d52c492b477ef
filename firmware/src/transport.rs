//! Which byte path the board layer serves: USART1 (always, on silicon and by default in QEMU) or, when
//! the host explicitly opts in, Arm semihosting (QEMU only).
//!
//! Why a second path: QEMU 7.2's STM32 USART model hands the guest one byte per main-loop round trip
//! (a socket read, a wake-up of the vCPU thread and an interrupt per byte), about 4-7 ms of wall time
//! per 20 Hz frame, which made the 20-minute flight take 2-3 minutes or more. Semihosting moves a
//! whole frame per call (`SYS_READ` on `:tt`, i.e. QEMU's stdin, and `SYS_WRITE` to its stdout), so
//! the link costs two host syscalls a frame. The bytes, and so the estimates, are the same on both
//! paths; the USART path stays covered by tests and is the only one on a board.
//!
//! The opt-in: a semihosting call (`BKPT 0xAB`) on a board with no debugger attached is a HardFault,
//! so the image never guesses. The host writes [`SEMIHOST_MAGIC`] at [`MAILBOX_ADDR`] before the core
//! starts (QEMU: `-device loader,addr=...,data=...,data-len=8`). The mailbox is the top 16 bytes of
//! SRAM, above the stack (`memory.x` sets `_stack_start` below it; QEMU does not model the CCM). On
//! silicon SRAM powers up with arbitrary contents; a 64-bit pattern matches by chance with probability
//! 2⁻⁶⁴, and the board clears the word once read, so a warm reset does not inherit it.

/// Where the host leaves the opt-in word: the top 16 bytes of the F407's 128 KiB SRAM, kept free by
/// `_stack_start` in `memory.x`.
pub const MAILBOX_ADDR: u32 = 0x2001_FFF0;

/// The addresses of the opt-in word's low and high halves.
pub const MAILBOX_WORDS: [u32; 2] = [MAILBOX_ADDR, MAILBOX_ADDR + 4];

/// The opt-in pattern, "SEMIHOST" in ASCII read as a big-endian 64-bit number.
pub const SEMIHOST_MAGIC: u64 = 0x5345_4D49_484F_5354;

/// The byte paths of the board layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum Transport {
    /// USART1 at 115 200 Bd, received in its interrupt.
    Usart,
    /// Semihosting reads and writes on the host's console (QEMU's stdin and stdout).
    Semihost,
}

impl Transport {
    /// The transport for the mailbox's two words as read from memory (low word at the lower
    /// address, little-endian as the Cortex-M4 stores a `u64`).
    pub fn from_mailbox(low: u32, high: u32) -> Transport {
        if (u64::from(high) << 32 | u64::from(low)) == SEMIHOST_MAGIC {
            Transport::Semihost
        } else {
            Transport::Usart
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_exact_pattern_opts_in() {
        let low = SEMIHOST_MAGIC as u32;
        let high = (SEMIHOST_MAGIC >> 32) as u32;
        assert_eq!(Transport::from_mailbox(low, high), Transport::Semihost);
        assert_eq!(Transport::from_mailbox(high, low), Transport::Usart);
        assert_eq!(Transport::from_mailbox(0, 0), Transport::Usart);
        assert_eq!(
            Transport::from_mailbox(u32::MAX, u32::MAX),
            Transport::Usart
        );
        assert_eq!(Transport::from_mailbox(low ^ 1, high), Transport::Usart);
        assert_eq!(
            Transport::from_mailbox(low, high ^ 0x8000_0000),
            Transport::Usart
        );
    }

    #[test]
    fn the_pattern_spells_semihost() {
        assert_eq!(&SEMIHOST_MAGIC.to_be_bytes(), b"SEMIHOST");
    }
}
