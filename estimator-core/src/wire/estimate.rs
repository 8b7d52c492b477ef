//! Estimate frames (estimator → hil-sim or the flight control computer).
//!
//! ```text
//! payload offset  field              type   unit
//!  0              alpha              i32    millidegrees
//!  4              beta               i32    millidegrees
//!  8              w_aero             i32    mm/s   (cascade part 1 for α)
//! 12              v_aero             i32    mm/s   (cascade part 1 for β)
//! 16              flags              u16    Flags bits
//! 18              step_ticks         u32    time of this step, in tick_source units
//! 22              tick_source        u8     0 none, 1 CPU cycles (DWT), 2 instructions (QEMU -icount), 3 host ns
//! 23              rx_corrupt         u32    frames the receiver rejected so far (COBS, CRC, length, version)
//! 27              rx_lost            u32    sensor frames never received (sequence gaps) so far
//! 31              deadline_misses    u32    steps that overran their 50 ms period so far
//! 35              rx_overruns        u32    receiver overruns before the frame decoder (a UART
//!                                           overrun, each losing at least one byte) so far [version 2]
//! 39              sigma_alpha        u16    1σ of alpha, millidegrees; 65535: none (held)  [version 4]
//! 41              sigma_beta         u16    1σ of beta, millidegrees; 65535: none (held)   [version 4]
//! ```
//! The header's seq and time echo the sensor frame answered. Version 1 of the wire format had no
//! `rx_overruns` (a 35-byte payload), versions 2 and 3 no 1σ (39 bytes); such a frame is refused
//! as [`Error::Version`], never misread.

use super::{
    Error, HEADER_LEN, Kind, check_header, emit_header, header_of, read_u16, read_u32, write,
};
use crate::estimator::{Estimate, Flags};

pub const PAYLOAD_LEN: usize = 43;
pub const BODY_LEN: usize = HEADER_LEN + PAYLOAD_LEN;

mod field {
    use super::HEADER_LEN;
    use core::ops::Range;
    // Only evaluated for the constants below: an overflow would be a compile error.
    #[allow(clippy::arithmetic_side_effects)]
    const fn at(o: usize, n: usize) -> Range<usize> {
        HEADER_LEN + o..HEADER_LEN + o + n
    }
    pub const ALPHA: Range<usize> = at(0, 4);
    pub const BETA: Range<usize> = at(4, 4);
    pub const W_AERO: Range<usize> = at(8, 4);
    pub const V_AERO: Range<usize> = at(12, 4);
    pub const FLAGS: Range<usize> = at(16, 2);
    pub const STEP_TICKS: Range<usize> = at(18, 4);
    pub const TICK_SOURCE: Range<usize> = at(22, 1);
    pub const RX_CORRUPT: Range<usize> = at(23, 4);
    pub const RX_LOST: Range<usize> = at(27, 4);
    pub const DEADLINE_MISSES: Range<usize> = at(31, 4);
    pub const RX_OVERRUNS: Range<usize> = at(35, 4);
    pub const SIGMA_ALPHA: Range<usize> = at(39, 2);
    pub const SIGMA_BETA: Range<usize> = at(41, 2);
}

/// What `step_ticks` counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum TickSource {
    #[default]
    None = 0,
    /// CPU cycles from the DWT cycle counter (silicon).
    Cycles = 1,
    /// Instructions retired (QEMU with `-icount shift=0`, via TIM2).
    Instructions = 2,
    /// Nanoseconds of host time (the in-process firmware).
    HostNanos = 3,
}

impl TickSource {
    fn from_u8(v: u8) -> TickSource {
        match v {
            1 => TickSource::Cycles,
            2 => TickSource::Instructions,
            3 => TickSource::HostNanos,
            _ => TickSource::None,
        }
    }
}

/// Link and timing counters the estimator side reports with every estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Health {
    pub step_ticks: u32,
    pub tick_source: TickSource,
    pub rx_corrupt: u32,
    pub rx_lost: u32,
    pub deadline_misses: u32,
    /// Received bytes the estimator side dropped before decoding them: its receive queue was full
    /// (steps too slow for the link) or the UART overran. Each one corrupts a frame, which then
    /// also counts in `rx_corrupt`.
    pub rx_overruns: u32,
}

/// The validated representation of an estimate frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EstimateFrame {
    pub estimate: Estimate,
    pub health: Health,
}

/// A checked, zero-copy view of an estimate frame body.
pub struct EstimatePacket<T: AsRef<[u8]>> {
    buf: T,
}

impl<T: AsRef<[u8]>> EstimatePacket<T> {
    pub fn new_checked(buf: T) -> Result<Self, Error> {
        check_header(buf.as_ref(), Kind::Estimate, PAYLOAD_LEN)?;
        Ok(EstimatePacket { buf })
    }
    fn u32(&self, r: core::ops::Range<usize>) -> u32 {
        read_u32(self.buf.as_ref(), r)
    }
    pub fn seq(&self) -> u16 {
        header_of(self.buf.as_ref()).0
    }
    pub fn time_ms(&self) -> u32 {
        header_of(self.buf.as_ref()).1
    }
    pub fn alpha_mdeg(&self) -> i32 {
        self.u32(field::ALPHA) as i32
    }
    pub fn beta_mdeg(&self) -> i32 {
        self.u32(field::BETA) as i32
    }
    pub fn flags(&self) -> u16 {
        read_u16(self.buf.as_ref(), field::FLAGS)
    }
}

impl EstimateFrame {
    pub fn parse(body: &[u8]) -> Result<EstimateFrame, Error> {
        let p = EstimatePacket::new_checked(body)?;
        let estimate = Estimate {
            seq: p.seq(),
            time_ms: p.time_ms(),
            alpha_mdeg: p.alpha_mdeg(),
            beta_mdeg: p.beta_mdeg(),
            w_aero_mms: p.u32(field::W_AERO) as i32,
            v_aero_mms: p.u32(field::V_AERO) as i32,
            flags: Flags(p.flags()),
            sigma_alpha_mdeg: read_u16(body, field::SIGMA_ALPHA),
            sigma_beta_mdeg: read_u16(body, field::SIGMA_BETA),
        };
        let src = body.get(field::TICK_SOURCE.start).copied().unwrap_or(0);
        let health = Health {
            step_ticks: p.u32(field::STEP_TICKS),
            tick_source: TickSource::from_u8(src),
            rx_corrupt: p.u32(field::RX_CORRUPT),
            rx_lost: p.u32(field::RX_LOST),
            deadline_misses: p.u32(field::DEADLINE_MISSES),
            rx_overruns: p.u32(field::RX_OVERRUNS),
        };
        Ok(EstimateFrame { estimate, health })
    }

    pub fn emit(&self, body: &mut [u8; BODY_LEN]) {
        let (e, h) = (&self.estimate, &self.health);
        emit_header(body, Kind::Estimate, e.seq, e.time_ms);
        write(body, field::ALPHA, &e.alpha_mdeg.to_le_bytes());
        write(body, field::BETA, &e.beta_mdeg.to_le_bytes());
        write(body, field::W_AERO, &e.w_aero_mms.to_le_bytes());
        write(body, field::V_AERO, &e.v_aero_mms.to_le_bytes());
        write(body, field::FLAGS, &e.flags.0.to_le_bytes());
        write(body, field::SIGMA_ALPHA, &e.sigma_alpha_mdeg.to_le_bytes());
        write(body, field::SIGMA_BETA, &e.sigma_beta_mdeg.to_le_bytes());
        write(body, field::STEP_TICKS, &h.step_ticks.to_le_bytes());
        write(body, field::TICK_SOURCE, &[h.tick_source as u8]);
        write(body, field::RX_CORRUPT, &h.rx_corrupt.to_le_bytes());
        write(body, field::RX_LOST, &h.rx_lost.to_le_bytes());
        write(
            body,
            field::DEADLINE_MISSES,
            &h.deadline_misses.to_le_bytes(),
        );
        write(body, field::RX_OVERRUNS, &h.rx_overruns.to_le_bytes());
    }

    /// The whole wire frame (CRC, COBS, delimiter). Returns its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        let mut body = [0u8; BODY_LEN];
        self.emit(&mut body);
        super::encode(&body, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let f = EstimateFrame {
            estimate: Estimate {
                seq: 65535,
                time_ms: 123_456,
                alpha_mdeg: -4321,
                beta_mdeg: 987,
                w_aero_mms: -12_000,
                v_aero_mms: 345,
                flags: Flags(Flags::OUT_OF_ENVELOPE | Flags::BETA_HELD),
                sigma_alpha_mdeg: 412,
                sigma_beta_mdeg: crate::uncertainty::SIGMA_UNKNOWN,
            },
            health: Health {
                step_ticks: 812_345,
                tick_source: TickSource::Instructions,
                rx_corrupt: 3,
                rx_lost: 2,
                deadline_misses: 0,
                rx_overruns: 7,
            },
        };
        let mut wire = [0u8; super::super::MAX_FRAME];
        let n = f.encode(&mut wire).unwrap();
        let mut out = [0u8; super::super::MAX_FRAME];
        let body = super::super::decode(&wire[..n - 1], &mut out).unwrap();
        assert_eq!(EstimateFrame::parse(body).unwrap(), f);
        assert_eq!(
            EstimateFrame::parse(&body[..BODY_LEN - 1]),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn fields_land_at_their_documented_offsets() {
        let mut f = EstimateFrame::default();
        f.health.deadline_misses = 0x0102_0304;
        f.health.rx_overruns = 0x0506_0708;
        f.estimate.sigma_alpha_mdeg = 0x0a0b;
        f.estimate.sigma_beta_mdeg = 0x0c0d;
        let mut body = [0u8; BODY_LEN];
        f.emit(&mut body);
        assert_eq!(body[0], super::super::VERSION);
        assert_eq!(
            &body[HEADER_LEN + 31..HEADER_LEN + 35],
            &0x0102_0304u32.to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 35..HEADER_LEN + 39],
            &0x0506_0708u32.to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 39..HEADER_LEN + 41],
            &0x0a0bu16.to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 41..HEADER_LEN + 43],
            &0x0c0du16.to_le_bytes()
        );
        assert_eq!(BODY_LEN, HEADER_LEN + 43);
    }

    /// Version 1 estimate frames were 8 bytes shorter (no `rx_overruns`, no 1σ), versions 2 and 3
    /// 4 bytes (no 1σ): one must be refused as a version mismatch, not read with this layout nor
    /// reported as merely truncated.
    #[test]
    fn a_frame_of_another_version_is_refused_as_such() {
        let f = EstimateFrame::default();
        let mut body = [0u8; BODY_LEN];
        f.emit(&mut body);
        let mut v1 = body;
        v1[0] = 1;
        assert_eq!(
            EstimateFrame::parse(&v1[..HEADER_LEN + 35]),
            Err(Error::Version(1))
        );
        assert_eq!(EstimateFrame::parse(&v1), Err(Error::Version(1)));
        let mut v3 = body;
        v3[0] = 3;
        assert_eq!(
            EstimateFrame::parse(&v3[..HEADER_LEN + 39]),
            Err(Error::Version(3))
        );
        for other in [2, 3, 4, 5, 7] {
            let mut v = body;
            v[0] = other;
            assert_eq!(EstimateFrame::parse(&v), Err(Error::Version(other)));
        }
        // Through the whole stream too: the receiver decodes the frame (CRC fine) and refuses it.
        let mut wire = [0u8; super::super::MAX_FRAME];
        let n = super::super::encode(&v1[..HEADER_LEN + 35], &mut wire).unwrap();
        let mut acc = super::super::Accumulator::<{ super::super::MAX_FRAME }>::new();
        let got: Vec<_> = wire[..n]
            .iter()
            .filter_map(|b| acc.push(*b).map(|r| r.and_then(EstimateFrame::parse)))
            .collect();
        assert_eq!(got, [Err(Error::Version(1))]);
        assert_eq!(
            std::format!("{}", Error::Version(1)),
            "wire format version 1, but this build speaks version 6"
        );
    }
}
