//! A fixed-capacity, lock-free single-producer/single-consumer byte queue between the receive
//! interrupt (the one producer) and the main loop (the one consumer). It never allocates, never
//! blocks and never panics.
//!
//! Lamport's ring buffer: the producer alone writes `tail` and the slot there, the consumer alone
//! writes `head`. The producer publishes a byte with a `Release` store of `tail` after writing its
//! slot, and the consumer `Acquire`-loads `tail` before reading it; the consumer frees a slot with a
//! `Release` store of `head`, which the producer `Acquire`-loads before writing over it. Every slot is
//! an `AtomicU8`, so the queue is shared as a plain `static` through `&self`: no lock, no critical
//! section, no `RefCell` (whose borrow check was a panic path in the interrupt) and no `unsafe`.
//! Two producers or two consumers at once would lose or repeat bytes, but even that stays memory
//! safe; the board layer has exactly one of each.
//!
//! `head` and `tail` count modulo `2 × N`, so a full queue (`N` bytes) and an empty one differ.

use core::sync::atomic::{AtomicU8, AtomicU32, AtomicUsize, Ordering};

/// FIFO of at most `N` bytes. A full queue hands the byte back (`Err`) and counts it as an overrun.
pub struct ByteQueue<const N: usize> {
    slots: [AtomicU8; N],
    /// Next position to read, in `0..2N`; written by the consumer only.
    head: AtomicUsize,
    /// Next position to write, in `0..2N`; written by the producer only.
    tail: AtomicUsize,
    /// Bytes dropped before the consumer saw them; written by the producer only.
    overruns: AtomicU32,
}

impl<const N: usize> Default for ByteQueue<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ByteQueue<N> {
    /// Positions run over `0..LAPS`: twice the capacity, so that full and empty differ.
    const LAPS: usize = 2 * N;

    pub const fn new() -> Self {
        const {
            assert!(N > 0, "a queue holds at least one byte");
            assert!(
                N <= usize::MAX / 4,
                "positions run to 2N, sums of two to 4N"
            );
        }
        ByteQueue {
            slots: [const { AtomicU8::new(0) }; N],
            head: AtomicUsize::new(0),
            tail: AtomicUsize::new(0),
            overruns: AtomicU32::new(0),
        }
    }

    /// The position after `i` (`i < LAPS`).
    fn next(i: usize) -> usize {
        let j = i.wrapping_add(1); // i < 2N <= usize::MAX / 2: cannot wrap
        if j >= Self::LAPS { 0 } else { j }
    }

    /// The slot of position `i` (`i < LAPS`).
    fn slot(&self, i: usize) -> Option<&AtomicU8> {
        self.slots.get(if i >= N { i.wrapping_sub(N) } else { i })
    }

    /// Bytes between two positions (`head`, `tail` < LAPS): at most `N`.
    fn between(head: usize, tail: usize) -> usize {
        // Positions are modulo LAPS; neither branch can wrap (both are below LAPS <= usize::MAX / 2).
        if tail >= head {
            tail.wrapping_sub(head)
        } else {
            tail.wrapping_add(Self::LAPS).wrapping_sub(head)
        }
    }

    /// Producer side: appends a byte, or hands it back and counts an overrun if the queue is full.
    pub fn push(&self, byte: u8) -> Result<(), u8> {
        let tail = self.tail.load(Ordering::Relaxed); // our own
        let head = self.head.load(Ordering::Acquire); // the consumer is done with the slots before it
        let Some(slot) = self.slot(tail).filter(|_| Self::between(head, tail) < N) else {
            self.count_overrun();
            return Err(byte);
        };
        slot.store(byte, Ordering::Relaxed);
        self.tail.store(Self::next(tail), Ordering::Release); // publishes the slot
        Ok(())
    }

    /// Producer side: counts a byte lost before it could even be pushed (e.g. a UART overrun).
    pub fn count_overrun(&self) {
        // One writer (the producer), so a load and a store need no read-modify-write. A count
        // saturates rather than wrap back to small numbers.
        let n = self.overruns.load(Ordering::Relaxed);
        self.overruns.store(n.saturating_add(1), Ordering::Relaxed);
    }

    /// Consumer side: the oldest byte, if any.
    pub fn pop(&self) -> Option<u8> {
        let head = self.head.load(Ordering::Relaxed); // our own
        let tail = self.tail.load(Ordering::Acquire); // the slots before it are written
        if head == tail {
            return None;
        }
        let byte = self.slot(head)?.load(Ordering::Relaxed);
        self.head.store(Self::next(head), Ordering::Release); // hands the slot back
        Some(byte)
    }

    pub fn len(&self) -> usize {
        Self::between(
            self.head.load(Ordering::Acquire),
            self.tail.load(Ordering::Acquire),
        )
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether a push now would be refused. Only the consumer makes room, so a producer that sees
    /// `false` can push.
    pub fn is_full(&self) -> bool {
        self.len() >= N
    }

    pub const fn capacity(&self) -> usize {
        N
    }

    /// Bytes dropped so far because the queue was full or the producer could not take them (each
    /// one corrupts the frame it belonged to, which the CRC then rejects). Saturates at `u32::MAX`.
    pub fn overruns(&self) -> u32 {
        self.overruns.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifo_order_across_the_wrap() {
        let q = ByteQueue::<4>::new();
        for round in 0..10u8 {
            q.push(round).unwrap();
            q.push(round.wrapping_add(100)).unwrap();
            assert_eq!(q.len(), 2);
            assert_eq!(q.pop(), Some(round));
            assert_eq!(q.pop(), Some(round.wrapping_add(100)));
            assert!(q.is_empty());
        }
        assert_eq!(q.pop(), None);
    }

    #[test]
    fn full_queue_hands_the_byte_back_and_counts_it() {
        let q = ByteQueue::<3>::new();
        for b in 1..=3 {
            assert!(!q.is_full());
            q.push(b).unwrap();
        }
        assert_eq!(q.len(), 3);
        assert!(q.is_full());
        assert_eq!(q.push(9), Err(9));
        assert_eq!(q.push(10), Err(10));
        assert_eq!(q.overruns(), 2);
        assert_eq!(
            (q.pop(), q.pop(), q.pop(), q.pop()),
            (Some(1), Some(2), Some(3), None)
        );
        assert!(!q.is_full());
        q.push(4).unwrap();
        assert_eq!(q.pop(), Some(4));
        q.count_overrun();
        assert_eq!(q.overruns(), 3);
    }

    #[test]
    fn full_and_empty_are_told_apart_at_every_position() {
        let q = ByteQueue::<5>::new();
        for start in 0..12u8 {
            for b in 0..5 {
                q.push(start.wrapping_add(b)).unwrap();
            }
            assert_eq!(q.len(), 5);
            assert_eq!(q.push(0xEE), Err(0xEE));
            for b in 0..5 {
                assert_eq!(q.pop(), Some(start.wrapping_add(b)));
            }
            assert_eq!(q.pop(), None);
            q.push(start).unwrap(); // shifts the start position by one each round
            assert_eq!(q.pop(), Some(start));
        }
    }

    /// A producer and a consumer thread at once (the interrupt and the main loop on the board): every
    /// byte arrives once and in order, and the refused ones are exactly the overruns counted.
    #[test]
    fn concurrent_producer_and_consumer_keep_order() {
        const BYTES: u32 = 200_000;
        let q = ByteQueue::<16>::new();
        let (received, refused) = std::thread::scope(|s| {
            let producer = s.spawn(|| {
                let mut refused = 0u32;
                let mut i = 0u32;
                while i < BYTES {
                    if q.push(i as u8).is_ok() {
                        i += 1;
                    } else {
                        refused += 1;
                        std::thread::yield_now();
                    }
                }
                refused
            });
            let mut received = 0u32;
            while received < BYTES {
                match q.pop() {
                    Some(b) => {
                        assert_eq!(b, received as u8, "byte {received} out of order");
                        received += 1;
                    }
                    None => std::hint::spin_loop(),
                }
            }
            (received, producer.join().unwrap())
        });
        assert_eq!(received, BYTES);
        assert_eq!(q.overruns(), refused);
        assert!(q.is_empty());
    }
}
