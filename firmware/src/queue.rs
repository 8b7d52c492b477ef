//! A fixed-capacity byte FIFO between the receive interrupt (producer) and the main loop (consumer).
//! The board layer guards it with a critical section; it never allocates and never panics.

/// FIFO of at most `N` bytes. A full queue hands the byte back (`Err`) and counts it as an overrun.
pub struct ByteQueue<const N: usize> {
    buf: [u8; N],
    head: usize,
    len: usize,
    overruns: u32,
}

impl<const N: usize> Default for ByteQueue<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ByteQueue<N> {
    pub const fn new() -> Self {
        ByteQueue {
            buf: [0; N],
            head: 0,
            len: 0,
            overruns: 0,
        }
    }

    pub fn push(&mut self, byte: u8) -> Result<(), u8> {
        if self.len >= N {
            self.overruns = self.overruns.saturating_add(1);
            return Err(byte);
        }
        let at = (self.head + self.len) % N;
        match self.buf.get_mut(at) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
                Ok(())
            }
            None => Err(byte),
        }
    }

    pub fn pop(&mut self) -> Option<u8> {
        if self.len == 0 {
            return None;
        }
        let b = self.buf.get(self.head).copied();
        self.head = (self.head + 1) % N;
        self.len -= 1;
        b
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub const fn capacity(&self) -> usize {
        N
    }

    /// Bytes dropped because the queue was full (each one corrupts the frame it belonged to, which the
    /// CRC then rejects).
    pub fn overruns(&self) -> u32 {
        self.overruns
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifo_order_across_the_wrap() {
        let mut q = ByteQueue::<4>::new();
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
        let mut q = ByteQueue::<3>::new();
        for b in 1..=3 {
            q.push(b).unwrap();
        }
        assert_eq!(q.push(9), Err(9));
        assert_eq!(q.push(10), Err(10));
        assert_eq!(q.overruns(), 2);
        assert_eq!(
            (q.pop(), q.pop(), q.pop(), q.pop()),
            (Some(1), Some(2), Some(3), None)
        );
        q.push(4).unwrap();
        assert_eq!(q.pop(), Some(4));
    }
}
