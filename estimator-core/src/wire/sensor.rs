//! Sensor frames (hil-sim or the sensor bus → estimator).
//!
//! ```text
//! payload offset  field                          type      unit
//!  0              gyro p, q, r                   3 × i32   µrad/s
//! 12              specific force x, y, z         3 × i32   1e-5 m/s²
//! 24              GPS speed                      i32       mm/s
//! 28              GPS altitude MSL               i32       cm
//! 32              elevator, aileron, rudder,     7 × i16   0.01°
//!                 LEF, TEF, flaperon, speedbrake
//! 46              throttle                       u16       1e-4
//! 48              valid                          u16       bit per channel, in channel order
//! ```

use super::{
    Error, HEADER_LEN, Kind, check_header, emit_header, header_of, read_u16, read_u32, write,
};
use crate::channels::{CHANNELS, Channel, SensorFrame};

pub const PAYLOAD_LEN: usize = 50;
pub const BODY_LEN: usize = HEADER_LEN + PAYLOAD_LEN;

mod field {
    use super::HEADER_LEN;
    /// Start of the 32-bit channels (gyro, accel, GPS): 8 × i32.
    pub const WIDE: usize = HEADER_LEN;
    /// Start of the 16-bit channels (surfaces, throttle): 8 × i16/u16.
    pub const NARROW: usize = HEADER_LEN + 32;
    pub const VALID: core::ops::Range<usize> = HEADER_LEN + 48..HEADER_LEN + 50;
}

/// Number of 32-bit channels; the rest are 16-bit.
const WIDE: usize = 8;

// A channel index is below 16: none of these operations can overflow.
#[allow(clippy::arithmetic_side_effects)]
fn channel_range(c: Channel) -> core::ops::Range<usize> {
    let i = c.index();
    if i < WIDE {
        let s = field::WIDE + 4 * i;
        s..s + 4
    } else {
        let s = field::NARROW + 2 * (i - WIDE);
        s..s + 2
    }
}

/// A checked, zero-copy view of a sensor frame body (header + payload, CRC already removed).
pub struct SensorPacket<T: AsRef<[u8]>> {
    buf: T,
}

impl<T: AsRef<[u8]>> SensorPacket<T> {
    /// Checks length, version and kind once; the accessors then never fail.
    pub fn new_checked(buf: T) -> Result<Self, Error> {
        check_header(buf.as_ref(), Kind::Sensor, PAYLOAD_LEN)?;
        Ok(SensorPacket { buf })
    }

    pub fn seq(&self) -> u16 {
        header_of(self.buf.as_ref()).0
    }

    pub fn time_ms(&self) -> u32 {
        header_of(self.buf.as_ref()).1
    }

    pub fn channel(&self, c: Channel) -> i32 {
        let b = self.buf.as_ref();
        let r = channel_range(c);
        match c {
            Channel::Throttle => read_u16(b, r) as i32,
            _ if c.index() >= WIDE => read_u16(b, r) as i16 as i32,
            _ => read_u32(b, r) as i32,
        }
    }

    pub fn valid(&self) -> u16 {
        read_u16(self.buf.as_ref(), field::VALID)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> SensorPacket<T> {
    /// A writable view over a buffer of at least [`BODY_LEN`] bytes.
    pub fn new_unchecked(buf: T) -> Self {
        SensorPacket { buf }
    }

    pub fn into_inner(self) -> T {
        self.buf
    }
}

impl SensorFrame {
    /// Parses a checked body. Channel bits above [`CHANNELS`] are ignored.
    pub fn parse(body: &[u8]) -> Result<SensorFrame, Error> {
        let p = SensorPacket::new_checked(body)?;
        let mut raw = [0i32; CHANNELS];
        for (r, c) in raw.iter_mut().zip(Channel::ALL) {
            *r = p.channel(c);
        }
        Ok(SensorFrame {
            seq: p.seq(),
            time_ms: p.time_ms(),
            raw,
            valid: p.valid() & crate::channels::ALL_VALID,
        })
    }

    /// Writes the body into `p`. Values that do not fit a 16-bit channel are saturated and marked invalid.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, p: &mut SensorPacket<T>) {
        let b = p.buf.as_mut();
        emit_header(b, Kind::Sensor, self.seq, self.time_ms);
        let mut valid = self.valid & crate::channels::ALL_VALID;
        for (c, v) in Channel::ALL.iter().zip(self.raw) {
            let r = channel_range(*c);
            let (lo, hi) = c.raw_range();
            if v < lo || v > hi {
                valid &= !c.bit();
            }
            let v = v.clamp(lo, hi);
            match c.index() {
                i if i < WIDE => write(b, r, &v.to_le_bytes()),
                _ if *c == Channel::Throttle => write(b, r, &(v as u16).to_le_bytes()),
                _ => write(b, r, &(v as i16).to_le_bytes()),
            }
        }
        write(b, field::VALID, &valid.to_le_bytes());
    }

    /// The whole wire frame (CRC, COBS, delimiter). Returns its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        let mut body = [0u8; BODY_LEN];
        self.emit(&mut SensorPacket::new_unchecked(&mut body[..]));
        super::encode(&body, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_land_at_their_documented_offsets() {
        let mut f = SensorFrame {
            seq: 0x0102,
            time_ms: 0x0304_0506,
            raw: [0; CHANNELS],
            valid: 0xFFFF,
        };
        f.raw[Channel::GyroR.index()] = -2;
        f.raw[Channel::Rudder.index()] = -3;
        f.raw[Channel::Throttle.index()] = 60000;
        let mut body = [0u8; BODY_LEN];
        f.emit(&mut SensorPacket::new_unchecked(&mut body[..]));
        let version = super::super::VERSION;
        assert_eq!(
            &body[..8],
            &[version, 1, 0x02, 0x01, 0x06, 0x05, 0x04, 0x03]
        );
        assert_eq!(&body[8 + 8..8 + 12], &(-2i32).to_le_bytes());
        assert_eq!(&body[8 + 36..8 + 38], &(-3i16).to_le_bytes());
        assert_eq!(&body[8 + 46..8 + 48], &60000u16.to_le_bytes());
        assert_eq!(&body[8 + 48..8 + 50], &0xFFFFu16.to_le_bytes());
        let back = SensorFrame::parse(&body).unwrap();
        assert_eq!(back.raw, f.raw);
        assert_eq!(back.valid, crate::channels::ALL_VALID);
    }

    #[test]
    fn out_of_range_narrow_channels_are_saturated_and_invalid() {
        let mut f = SensorFrame {
            valid: crate::channels::ALL_VALID,
            ..SensorFrame::default()
        };
        f.raw[Channel::Elevator.index()] = 40_000;
        f.raw[Channel::Throttle.index()] = -1;
        let mut body = [0u8; BODY_LEN];
        f.emit(&mut SensorPacket::new_unchecked(&mut body[..]));
        let back = SensorFrame::parse(&body).unwrap();
        assert_eq!(back.get(Channel::Elevator), i16::MAX as i32);
        assert!(!back.is_valid(Channel::Elevator));
        assert!(!back.is_valid(Channel::Throttle));
        assert!(back.is_valid(Channel::Rudder));
    }

    #[test]
    fn wrong_length_version_and_kind_are_errors() {
        let body = [0u8; BODY_LEN];
        assert_eq!(SensorFrame::parse(&body[..10]), Err(Error::Truncated));
        assert_eq!(
            SensorFrame::parse(&[0u8; BODY_LEN + 1]),
            Err(Error::TooLong)
        );
        assert_eq!(SensorFrame::parse(&body), Err(Error::Version(0)));
        let mut b = body;
        b[0] = super::super::VERSION;
        b[1] = Kind::Estimate as u8;
        assert_eq!(SensorFrame::parse(&b), Err(Error::Kind(2)));
    }
}
