//! The USART1 receive interrupt's work, apart from the board so that it is tested on the host: move
//! every byte the UART holds into the receive queue, and stop, leaving the byte in the UART, when
//! the queue is full (the board layer then masks the interrupt until the main loop has taken bytes).

use crate::queue::ByteQueue;
use crate::rcc::Mmio;

/// USART1's base address, its status register (RM0090 §30.6.1) and its data register.
pub const USART1: u32 = 0x4001_1000;
pub const USART1_SR: u32 = USART1;
pub const USART1_DR: u32 = USART1 + 0x04;
/// Overrun: a byte arrived while the previous one was still in DR and was lost.
pub const SR_ORE: u32 = 1 << 3;
/// A received byte waits in DR.
pub const SR_RXNE: u32 = 1 << 5;

/// How a pass of [`service_rx`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Serviced {
    /// The UART holds no byte and no overrun.
    Drained,
    /// The queue is full: the waiting byte stays in DR, unread.
    QueueFull,
}

/// Takes each byte waiting in USART1 into `rx` until the UART is empty or `rx` is full. Reading SR
/// then DR clears RXNE and an overrun; an overrun (which raises the interrupt too) is counted in
/// `rx`. A full queue leaves the byte in DR: under QEMU the USART then holds the next bytes back, on
/// a board the UART overruns and the next pass counts it.
pub fn service_rx<M: Mmio, const N: usize>(mmio: &mut M, rx: &ByteQueue<N>) -> Serviced {
    loop {
        let sr = mmio.read(USART1_SR);
        if sr & (SR_RXNE | SR_ORE) == 0 {
            return Serviced::Drained;
        }
        if rx.is_full() {
            return Serviced::QueueFull;
        }
        let [byte, ..] = mmio.read(USART1_DR).to_le_bytes();
        if sr & SR_ORE != 0 {
            rx.count_overrun();
        }
        if sr & SR_RXNE != 0 {
            // Not full (above), and only the consumer changes that: the push cannot be refused.
            let _ = rx.push(byte);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;

    /// A UART whose line delivers the next byte only once DR has been read, as QEMU's USART does;
    /// `ore` stands for a byte a board's UART lost.
    struct Uart {
        line: VecDeque<u8>,
        dr: Option<u8>,
        ore: bool,
    }

    impl Uart {
        fn with(bytes: &[u8]) -> Uart {
            let mut u = Uart {
                line: bytes.iter().copied().collect(),
                dr: None,
                ore: false,
            };
            u.dr = u.line.pop_front();
            u
        }
    }

    impl Mmio for Uart {
        fn read(&mut self, addr: u32) -> u32 {
            match addr {
                USART1_SR => {
                    (if self.dr.is_some() { SR_RXNE } else { 0 })
                        | (if self.ore { SR_ORE } else { 0 })
                }
                USART1_DR => {
                    let b = self.dr.take().unwrap_or(0);
                    self.ore = false;
                    self.dr = self.line.pop_front();
                    u32::from(b)
                }
                _ => panic!("read of {addr:#x}"),
            }
        }
        fn write(&mut self, addr: u32, _: u32) {
            panic!("write to {addr:#x}");
        }
    }

    fn drain<const N: usize>(q: &ByteQueue<N>) -> Vec<u8> {
        core::iter::from_fn(|| q.pop()).collect()
    }

    #[test]
    fn a_full_queue_leaves_the_byte_in_the_uart_and_loses_none() {
        let bytes: Vec<u8> = (1..=10).collect();
        let mut uart = Uart::with(&bytes);
        let q = ByteQueue::<4>::new();
        assert_eq!(service_rx(&mut uart, &q), Serviced::QueueFull);
        assert_eq!(uart.dr, Some(5), "the fifth byte stays in DR");
        let mut got = drain(&q);
        // The main loop takes bytes, the interrupt (unmasked) runs again, until the line is empty.
        while service_rx(&mut uart, &q) == Serviced::QueueFull {
            got.extend(drain(&q));
        }
        got.extend(drain(&q));
        assert_eq!(got, bytes);
        assert_eq!(q.overruns(), 0);
    }

    #[test]
    fn an_overrun_is_counted_and_the_byte_in_dr_kept() {
        let mut uart = Uart::with(&[7, 8]);
        uart.ore = true;
        let q = ByteQueue::<4>::new();
        assert_eq!(service_rx(&mut uart, &q), Serviced::Drained);
        assert_eq!(drain(&q), [7, 8]);
        assert_eq!(q.overruns(), 1);
    }

    #[test]
    fn an_overrun_alone_is_cleared_without_a_byte() {
        let mut uart = Uart::with(&[]);
        uart.ore = true;
        let q = ByteQueue::<4>::new();
        assert_eq!(service_rx(&mut uart, &q), Serviced::Drained);
        assert!(!uart.ore);
        assert!(q.is_empty());
        assert_eq!(q.overruns(), 1);
    }
}
