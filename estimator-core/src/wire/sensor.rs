//! Sensor frames (hil-sim or the sensor bus → estimator), one kind per sensor suite.
//!
//! Kind 1 `Sensor`, the Table 1 suite ([`Suite::Table1`]), 50-byte payload:
//! ```text
//! payload offset  field                          type      unit
//!  0              gyro p, q, r                   3 × i32   µrad/s
//! 12              specific force x, y, z         3 × i32   1e-5 m/s²
//! 24              GPS speed                      i32       mm/s
//! 28              GPS altitude MSL               i32       cm
//! 32              elevator, aileron, rudder,     7 × i16   0.01°
//!                 LEF, TEF, flaperon, speedbrake
//! 46              throttle                       u16       1e-4
//! 48              valid                          u16       bit per channel 0–15, in channel order
//! ```
//! Kind 3 `SensorEgi`, the EGI suite ([`Suite::Egi`]), 78-byte payload: the 50 bytes above, byte
//! for byte, then
//! ```text
//! payload offset  field                          type      unit
//! 50              roll, pitch, heading           3 × i32   µrad (heading in [0, 2π))
//! 62              velocity north, east, down     3 × i32   mm/s
//! 74              fuel quantity                  u16       0.1 kg
//! 76              valid (EGI)                    u16       bit k: channel 16 + k (bits 7–15 zero)
//! ```
//! Kind 4 `SensorEgi120`, the EGI suite with the 120 Hz sub-samples ([`Suite::Egi120`]), 308-byte
//! payload: the 78 bytes above, byte for byte, then
//! ```text
//! payload offset  field                          type      unit
//! 78              valid (sub-samples)            u16       bit i: SUB_CHANNELS[i] valid in all six
//!                                                          (bits 13–15 zero)
//! 80 + 38·k       sub-sample k = 0…5 (oldest first; k = 5 at the header's time_ms):
//!   + 0             gyro p, q, r                 3 × i32   µrad/s
//!   + 12            specific force x, y, z       3 × i32   1e-5 m/s²
//!   + 24            elevator, aileron, rudder,   7 × i16   0.01°
//!                   LEF, TEF, flaperon, speedbrake
//! ```
//! A kind-1 frame decodes with the EGI channels invalid (raw 0): nothing of a Table 1 frame is read
//! as EGI data. A kind-1 or kind-3 frame decodes without sub-samples ([`Subsamples::NONE`]). The sender chooses the kind ([`SensorFrame::encode`]); encoding a frame as kind 1
//! leaves its EGI channels out.

use super::{
    Error, HEADER_LEN, Kind, check_header, emit_header, header_of, read_u16, read_u32, write,
};
use crate::channels::{
    ALL_VALID, CHANNELS, Channel, SUB_CHANNELS, SUBSAMPLES, SensorFrame, Subsamples, Suite,
    TABLE1_CHANNELS,
};

/// Payload of a kind-1 (Table 1) sensor frame.
pub const PAYLOAD_LEN: usize = 50;
pub const BODY_LEN: usize = HEADER_LEN + PAYLOAD_LEN;
/// Payload of a kind-3 (EGI) sensor frame.
pub const EGI_PAYLOAD_LEN: usize = 78;
pub const EGI_BODY_LEN: usize = HEADER_LEN + EGI_PAYLOAD_LEN;
/// Bytes of one sub-sample in a kind-4 frame: six i32 IMU axes, seven i16 surfaces.
const SUB_LEN: usize = 6 * 4 + 7 * 2;
/// Payload of a kind-4 (EGI + 120 Hz sub-samples) sensor frame.
pub const EGI120_PAYLOAD_LEN: usize = EGI_PAYLOAD_LEN + 2 + SUBSAMPLES * SUB_LEN;
pub const EGI120_BODY_LEN: usize = HEADER_LEN + EGI120_PAYLOAD_LEN;

mod field {
    use super::HEADER_LEN;
    use core::ops::Range;
    /// Start of the 32-bit Table 1 channels (gyro, accel, GPS): 8 × i32.
    pub const WIDE: usize = HEADER_LEN;
    /// Start of the 16-bit Table 1 channels (surfaces, throttle): 8 × i16/u16.
    pub const NARROW: usize = HEADER_LEN + 32;
    pub const VALID: Range<usize> = HEADER_LEN + 48..HEADER_LEN + 50;
    /// Start of the 32-bit EGI channels (attitude, velocity): 6 × i32.
    pub const EGI_WIDE: usize = HEADER_LEN + 50;
    pub const FUEL: Range<usize> = HEADER_LEN + 74..HEADER_LEN + 76;
    pub const EGI_VALID: Range<usize> = HEADER_LEN + 76..HEADER_LEN + 78;
    pub const SUB_VALID: Range<usize> = HEADER_LEN + 78..HEADER_LEN + 80;
    /// Start of the sub-samples.
    pub const SUB: usize = HEADER_LEN + 80;
}

/// Where sub-sample `k` of `SUB_CHANNELS[i]` sits in a kind-4 body: the IMU's six first (i32),
/// then the surfaces (i16), each in its channel's wire width ([`narrow`]).
// k < 6 and i < 13: far from overflowing.
#[allow(clippy::arithmetic_side_effects)]
fn sub_range(k: usize, i: usize) -> core::ops::Range<usize> {
    let s = field::SUB + SUB_LEN * k;
    if i < 6 {
        s + 4 * i..s + 4 * i + 4
    } else {
        s + 24 + 2 * (i - 6)..s + 24 + 2 * (i - 6) + 2
    }
}

/// Channel `c`'s raw value at `r`, in its wire width and signedness ([`narrow`]).
fn read_value(b: &[u8], r: core::ops::Range<usize>, c: Channel) -> i32 {
    match narrow(c) {
        Some(false) => read_u16(b, r) as i32,
        Some(true) => read_u16(b, r) as i16 as i32,
        None => read_u32(b, r) as i32,
    }
}

/// Writes channel `c`'s raw value `v` at `r` in its wire width, saturated to the channel's range;
/// false when `v` was outside it (the value is then not valid).
fn write_value(b: &mut [u8], r: core::ops::Range<usize>, c: Channel, v: i32) -> bool {
    let (lo, hi) = c.raw_range();
    let w = v.clamp(lo, hi);
    match narrow(c) {
        None => write(b, r, &w.to_le_bytes()),
        Some(false) => write(b, r, &(w as u16).to_le_bytes()),
        Some(true) => write(b, r, &(w as i16).to_le_bytes()),
    }
    w == v
}

/// Number of 32-bit Table 1 channels; the rest of Table 1 is 16-bit.
const WIDE: usize = 8;

impl Suite {
    /// The frame kind that carries this suite.
    pub const fn kind(self) -> Kind {
        match self {
            Suite::Table1 => Kind::Sensor,
            Suite::Egi => Kind::SensorEgi,
            Suite::Egi120 => Kind::SensorEgi120,
        }
    }

    /// Payload length of this suite's sensor frames.
    pub const fn payload_len(self) -> usize {
        match self {
            Suite::Table1 => PAYLOAD_LEN,
            Suite::Egi => EGI_PAYLOAD_LEN,
            Suite::Egi120 => EGI120_PAYLOAD_LEN,
        }
    }
}

// A channel index is below 23: none of these operations can overflow.
#[allow(clippy::arithmetic_side_effects)]
fn channel_range(c: Channel) -> core::ops::Range<usize> {
    let i = c.index();
    if c == Channel::Fuel {
        field::FUEL
    } else if i >= TABLE1_CHANNELS {
        let s = field::EGI_WIDE + 4 * (i - TABLE1_CHANNELS);
        s..s + 4
    } else if i < WIDE {
        let s = field::WIDE + 4 * i;
        s..s + 4
    } else {
        let s = field::NARROW + 2 * (i - WIDE);
        s..s + 2
    }
}

/// Whether a channel is 16-bit on the wire (the others are i32), and unsigned.
fn narrow(c: Channel) -> Option<bool> {
    match c {
        Channel::Throttle | Channel::Fuel => Some(false),
        _ if (WIDE..TABLE1_CHANNELS).contains(&c.index()) => Some(true),
        _ => None,
    }
}

/// A checked, zero-copy view of a sensor frame body (header + payload, CRC already removed) of
/// either kind.
pub struct SensorPacket<T: AsRef<[u8]>> {
    buf: T,
    suite: Suite,
}

impl<T: AsRef<[u8]>> SensorPacket<T> {
    /// Checks version, length and kind once (a kind-3 header selects the EGI layout, anything else
    /// is judged as kind 1); the accessors then never fail.
    pub fn new_checked(buf: T) -> Result<Self, Error> {
        let b = buf.as_ref();
        let suite = match b.get(super::field::KIND) {
            Some(k) if *k == Kind::SensorEgi as u8 => Suite::Egi,
            Some(k) if *k == Kind::SensorEgi120 as u8 => Suite::Egi120,
            _ => Suite::Table1,
        };
        check_header(b, suite.kind(), suite.payload_len())?;
        Ok(SensorPacket { buf, suite })
    }

    /// The suite of this frame's kind.
    pub fn suite(&self) -> Suite {
        self.suite
    }

    pub fn seq(&self) -> u16 {
        header_of(self.buf.as_ref()).0
    }

    pub fn time_ms(&self) -> u32 {
        header_of(self.buf.as_ref()).1
    }

    /// A channel's raw value; 0 for a channel this frame's suite does not carry.
    pub fn channel(&self, c: Channel) -> i32 {
        if !self.suite.carries(c) {
            return 0;
        }
        read_value(self.buf.as_ref(), channel_range(c), c)
    }

    /// Bit per channel; channels the suite does not carry, and bits naming no channel, are clear.
    pub fn valid(&self) -> u32 {
        let b = self.buf.as_ref();
        let mut v = u32::from(read_u16(b, field::VALID));
        if self.suite != Suite::Table1 {
            v |= u32::from(read_u16(b, field::EGI_VALID)) << TABLE1_CHANNELS;
        }
        v & self.suite.channels() & ALL_VALID
    }

    /// The 120 Hz sub-samples of a kind-4 frame ([`Subsamples::NONE`] for the other kinds); bits
    /// naming no sub-channel are clear.
    pub fn subsamples(&self) -> Subsamples {
        if self.suite != Suite::Egi120 {
            return Subsamples::NONE;
        }
        let b = self.buf.as_ref();
        let mut s = Subsamples {
            valid: read_u16(b, field::SUB_VALID) & Subsamples::ALL_VALID,
            ..Subsamples::NONE
        };
        for (k, row) in s.raw.iter_mut().enumerate() {
            for (i, (v, c)) in row.iter_mut().zip(SUB_CHANNELS).enumerate() {
                *v = read_value(b, sub_range(k, i), c);
            }
        }
        s
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> SensorPacket<T> {
    /// A writable view of `suite`'s layout over a buffer of at least its body length
    /// ([`BODY_LEN`], [`EGI_BODY_LEN`]).
    pub fn new_unchecked(buf: T, suite: Suite) -> Self {
        SensorPacket { buf, suite }
    }

    pub fn into_inner(self) -> T {
        self.buf
    }
}

impl SensorFrame {
    /// Parses a checked body of either sensor kind. A kind-1 (Table 1) frame gives the EGI channels
    /// invalid and 0.
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
            valid: p.valid(),
            sub: p.subsamples(),
        })
    }

    /// Writes the body in the layout of `p`'s suite. Channels the suite does not carry are left out;
    /// values that do not fit a 16-bit channel are saturated and marked invalid.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, p: &mut SensorPacket<T>) {
        let suite = p.suite;
        let b = p.buf.as_mut();
        emit_header(b, suite.kind(), self.seq, self.time_ms);
        let mut valid = self.valid & suite.channels();
        for (c, v) in Channel::ALL.iter().zip(self.raw) {
            if !suite.carries(*c) {
                continue;
            }
            if !write_value(b, channel_range(*c), *c, v) {
                valid &= !c.bit();
            }
        }
        // The low 16 bits are the Table 1 channels, the next 7 the EGI ones (truncation intended).
        write(b, field::VALID, &(valid as u16).to_le_bytes());
        if suite != Suite::Table1 {
            let egi = ((valid & ALL_VALID) >> TABLE1_CHANNELS) as u16;
            write(b, field::EGI_VALID, &egi.to_le_bytes());
        }
        if suite == Suite::Egi120 {
            let mut sub_valid = self.sub.valid & Subsamples::ALL_VALID;
            for (k, row) in self.sub.raw.iter().enumerate() {
                for (i, (c, v)) in SUB_CHANNELS.iter().zip(row).enumerate() {
                    if !write_value(b, sub_range(k, i), *c, *v) {
                        sub_valid &= !(1 << i);
                    }
                }
            }
            write(b, field::SUB_VALID, &sub_valid.to_le_bytes());
        }
    }

    /// Writes the body of a frame of `suite` into `body`; returns its length, or `Buffer` if `body`
    /// is too short.
    pub fn emit_body(&self, suite: Suite, body: &mut [u8]) -> Result<usize, Error> {
        let n = HEADER_LEN.saturating_add(suite.payload_len());
        let b = body.get_mut(..n).ok_or(Error::Buffer)?;
        self.emit(&mut SensorPacket::new_unchecked(b, suite));
        Ok(n)
    }

    /// The whole wire frame of `suite`'s kind (CRC, COBS, delimiter). Returns its length. The
    /// sender's suite decides the kind: as [`Suite::Table1`] the EGI channels are not sent.
    pub fn encode(&self, suite: Suite, out: &mut [u8]) -> Result<usize, Error> {
        let mut body = [0u8; EGI120_BODY_LEN];
        let n = self.emit_body(suite, &mut body)?;
        super::encode(body.get(..n).ok_or(Error::Buffer)?, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channels::ALL_VALID;

    fn sample() -> SensorFrame {
        let mut f = SensorFrame {
            seq: 0x0102,
            time_ms: 0x0304_0506,
            raw: [0; CHANNELS],
            valid: u32::MAX,
            sub: crate::channels::Subsamples::NONE,
        };
        f.raw[Channel::GyroR.index()] = -2;
        f.raw[Channel::Rudder.index()] = -3;
        f.raw[Channel::Throttle.index()] = 60000;
        f.raw[Channel::Roll.index()] = -4;
        f.raw[Channel::Heading.index()] = 6_283_000;
        f.raw[Channel::VelDown.index()] = -5;
        f.raw[Channel::Fuel.index()] = 65_000;
        f
    }

    #[test]
    fn table1_fields_land_at_their_documented_offsets() {
        let f = sample();
        let mut body = [0u8; BODY_LEN];
        assert_eq!(f.emit_body(Suite::Table1, &mut body), Ok(BODY_LEN));
        let version = super::super::VERSION;
        assert_eq!(
            &body[..8],
            &[version, 1, 0x02, 0x01, 0x06, 0x05, 0x04, 0x03]
        );
        assert_eq!(
            &body[8..HEADER_LEN],
            &super::super::AIRCRAFT_TAG.to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 8..HEADER_LEN + 12],
            &(-2i32).to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 36..HEADER_LEN + 38],
            &(-3i16).to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 46..HEADER_LEN + 48],
            &60000u16.to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 48..HEADER_LEN + 50],
            &0xFFFFu16.to_le_bytes()
        );
        let back = SensorFrame::parse(&body).unwrap();
        assert_eq!(back, f.restricted_to(Suite::Table1));
        // A Table 1 frame decodes as Table 1: the EGI channels are absent, not zeros read as data.
        for c in Channel::ALL.iter().skip(TABLE1_CHANNELS) {
            assert!(!back.is_valid(*c), "{c:?}");
            assert_eq!(back.get(*c), 0);
        }
    }

    #[test]
    fn egi_fields_extend_the_table1_payload() {
        let f = sample();
        let mut t1 = [0u8; BODY_LEN];
        f.emit_body(Suite::Table1, &mut t1).unwrap();
        let mut body = [0u8; EGI_BODY_LEN];
        assert_eq!(f.emit_body(Suite::Egi, &mut body), Ok(EGI_BODY_LEN));
        assert_eq!(body[1], 3);
        // Same 50 payload bytes as the Table 1 frame, then the EGI block.
        assert_eq!(&body[2..BODY_LEN], &t1[2..]);
        assert_eq!(
            &body[HEADER_LEN + 50..HEADER_LEN + 54],
            &(-4i32).to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 58..HEADER_LEN + 62],
            &6_283_000i32.to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 70..HEADER_LEN + 74],
            &(-5i32).to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 74..HEADER_LEN + 76],
            &65_000u16.to_le_bytes()
        );
        assert_eq!(
            &body[HEADER_LEN + 76..HEADER_LEN + 78],
            &0x007Fu16.to_le_bytes()
        );
        let back = SensorFrame::parse(&body).unwrap();
        assert_eq!(back.raw, f.raw);
        assert_eq!(back.valid, ALL_VALID);
    }

    #[test]
    fn egi120_frames_carry_the_subsamples_after_the_egi_payload() {
        let mut f = sample();
        for (k, row) in f.sub.raw.iter_mut().enumerate() {
            for (i, v) in row.iter_mut().enumerate() {
                *v = (k as i32 * 100 + i as i32) * if i % 2 == 0 { 1 } else { -1 };
            }
        }
        f.sub.valid = Subsamples::ALL_VALID & !(1 << 8);
        let mut egi = [0u8; EGI_BODY_LEN];
        f.emit_body(Suite::Egi, &mut egi).unwrap();
        let mut body = [0u8; EGI120_BODY_LEN];
        assert_eq!(f.emit_body(Suite::Egi120, &mut body), Ok(HEADER_LEN + 308));
        assert_eq!(body[1], 4);
        // The EGI frame's payload byte for byte, then the sub-samples' validity and values.
        assert_eq!(&body[2..EGI_BODY_LEN], &egi[2..]);
        assert_eq!(
            &body[HEADER_LEN + 78..HEADER_LEN + 80],
            &0x1EFFu16.to_le_bytes()
        );
        // Sub-sample 5, specific force y (i = 4): 504 at 80 + 38·5 + 16.
        assert_eq!(
            &body[HEADER_LEN + 80 + 190 + 16..HEADER_LEN + 80 + 190 + 20],
            &504i32.to_le_bytes()
        );
        // Sub-sample 2, rudder (i = 8): 208 as i16 at 80 + 38·2 + 24 + 4.
        assert_eq!(
            &body[HEADER_LEN + 80 + 76 + 28..HEADER_LEN + 80 + 76 + 30],
            &208i16.to_le_bytes()
        );
        let back = SensorFrame::parse(&body).unwrap();
        assert_eq!(back.raw, f.raw);
        assert_eq!(back.sub, f.sub);
        assert!(!back.sub.is_valid(Channel::Rudder) && back.sub.is_valid(Channel::AccelY));
        assert_eq!(back.sub.get(5, Channel::AccelY), 504);
        assert_eq!(back.sub.get(5, Channel::AccelX), -503);
        // Bits above the 13 sub-channels name nothing and are ignored; a surface out of the i16
        // range is saturated and invalid; an EGI frame carries none.
        body[HEADER_LEN + 79] |= 0xE0;
        assert_eq!(SensorFrame::parse(&body).unwrap().sub.valid, f.sub.valid);
        f.sub.raw[3][6] = 40_000;
        f.emit_body(Suite::Egi120, &mut body).unwrap();
        let back = SensorFrame::parse(&body).unwrap();
        assert_eq!(back.sub.get(3, Channel::Elevator), i16::MAX as i32);
        assert!(!back.sub.is_valid(Channel::Elevator));
        assert_eq!(SensorFrame::parse(&egi).unwrap().sub, Subsamples::NONE);
    }

    #[test]
    fn egi_validity_bits_map_to_their_channels() {
        let mut f = sample();
        f.valid = ALL_VALID & !Channel::Pitch.bit() & !Channel::Elevator.bit();
        let mut body = [0u8; EGI_BODY_LEN];
        f.emit_body(Suite::Egi, &mut body).unwrap();
        assert_eq!(
            &body[HEADER_LEN + 76..HEADER_LEN + 78],
            &0b111_1101u16.to_le_bytes()
        );
        // Bits above the seven EGI channels name nothing and are ignored.
        body[HEADER_LEN + 77] = 0xFF;
        let back = SensorFrame::parse(&body).unwrap();
        assert_eq!(back.valid, f.valid);
    }

    #[test]
    fn out_of_range_narrow_channels_are_saturated_and_invalid() {
        let mut f = SensorFrame {
            valid: ALL_VALID,
            ..SensorFrame::default()
        };
        f.raw[Channel::Elevator.index()] = 40_000;
        f.raw[Channel::Throttle.index()] = -1;
        f.raw[Channel::Fuel.index()] = 70_000;
        let mut body = [0u8; EGI_BODY_LEN];
        f.emit_body(Suite::Egi, &mut body).unwrap();
        let back = SensorFrame::parse(&body).unwrap();
        assert_eq!(back.get(Channel::Elevator), i16::MAX as i32);
        assert!(!back.is_valid(Channel::Elevator));
        assert!(!back.is_valid(Channel::Throttle));
        assert_eq!(back.get(Channel::Fuel), u16::MAX as i32);
        assert!(!back.is_valid(Channel::Fuel));
        assert!(back.is_valid(Channel::Rudder));
        assert!(back.is_valid(Channel::Roll));
    }

    #[test]
    fn wrong_length_version_and_kind_are_errors() {
        let body = [0u8; EGI_BODY_LEN];
        assert_eq!(SensorFrame::parse(&body[..10]), Err(Error::Truncated));
        assert_eq!(
            SensorFrame::parse(&[0u8; BODY_LEN + 1]),
            Err(Error::TooLong)
        );
        assert_eq!(
            SensorFrame::parse(&body[..BODY_LEN]),
            Err(Error::Version(0))
        );
        let mut b = body;
        b[0] = super::super::VERSION;
        b[1] = Kind::Estimate as u8;
        assert_eq!(SensorFrame::parse(&b[..BODY_LEN]), Err(Error::Kind(2)));
        // Each kind has its own length: a Table 1 body labelled EGI is short, and the reverse long.
        b[1] = Kind::SensorEgi as u8;
        assert_eq!(SensorFrame::parse(&b[..BODY_LEN]), Err(Error::Truncated));
        b[1] = Kind::Sensor as u8;
        assert_eq!(SensorFrame::parse(&b), Err(Error::TooLong));
        // Another version is refused as such whatever the kind and length.
        for v in [1, 2, 3, 4, 5, 7, 255] {
            b[0] = v;
            b[1] = Kind::SensorEgi as u8;
            assert_eq!(SensorFrame::parse(&b), Err(Error::Version(v)));
            assert_eq!(SensorFrame::parse(&b[..BODY_LEN]), Err(Error::Version(v)));
        }
    }

    #[test]
    fn a_short_buffer_is_an_error_not_a_panic() {
        let mut small = [0u8; BODY_LEN];
        assert_eq!(
            sample().emit_body(Suite::Egi, &mut small),
            Err(Error::Buffer)
        );
        let mut out = [0u8; 20];
        assert_eq!(sample().encode(Suite::Table1, &mut out), Err(Error::Buffer));
    }
}
