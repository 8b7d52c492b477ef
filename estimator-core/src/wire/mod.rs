//! Frames on the serial link between `hil-sim` (or the aircraft's sensor bus) and the estimator.
//!
//! ```text
//! on the wire:  COBS( body | crc32 ) 0x00
//! body:         header (12 bytes) | payload (sensor: 50 bytes, sensor-egi: 78 bytes,
//!               sensor-egi120: 308 bytes, estimate: 43 bytes)
//! header:       version u8 | kind u8 | seq u16 | time_ms u32 | aircraft u32   (all little-endian)
//! crc32:        CRC-32/ISO-HDLC of the body, little-endian
//! ```
//!
//! COBS removes every 0x00 from the frame, so 0x00 marks frame ends: after garbage, a dropped byte or a
//! bit flip, the receiver discards at most the frame in progress and is in step again at the next
//! delimiter. The CRC rejects corrupted frames (all 1-, 2- and 3-bit errors and all bursts up to 32
//! bits in these lengths). Each payload has a zero-copy checked view (`*Packet<T: AsRef<[u8]>>`) and a
//! validated representation that parses from and emits into it ([`SensorFrame`](crate::SensorFrame),
//! [`EstimateFrame`](estimate::EstimateFrame)). Nothing here panics on any input.
//!
//! The kind names the sensor suite (or an estimate), and the aircraft field the airframe: the
//! CRC-32 of its description's name ([`aircraft_tag`]; `f16` 0xBAFCFCAB). A build carries one
//! aircraft's features, scaling and networks, so it refuses a frame of another aircraft as
//! [`Error::Aircraft`]: an F-16 image never computes an estimate from a light single's frame, which
//! has the same layout and very different numbers.
//!
//! The version byte names the layout of every frame kind. A receiver refuses a frame of another
//! version as [`Error::Version`] whatever its length (another version's frames may be longer or
//! shorter), so two builds that disagree fail loudly instead of misreading each other.
//!
//! | version | change |
//! |---|---|
//! | 1 | first format: sensor payload 50 bytes, estimate payload 35 bytes |
//! | 2 | estimate frames carry `rx_overruns` (payload 39 bytes); sensor frames unchanged |
//! | 3 | sensor suites: kind 3 `SensorEgi` (the 50-byte sensor payload + EGI attitude, velocity, fuel and their validity: 78 bytes) next to kind 1 `Sensor` (the Table 1 suite, layout unchanged); estimate frames unchanged |
//! | 4 | estimate frames carry the 1σ of α and β (payload 43 bytes); sensor frames unchanged |
//! | 5 | kind 4 `SensorEgi120` (the 78-byte EGI payload + the 120 Hz sub-samples of the frame period: 308 bytes) next to kinds 1 and 3 (layouts unchanged); estimate frames unchanged |
//! | 6 | the header names the aircraft (4 bytes more: 12); payloads unchanged |
//!
//! A receiver of version 6 takes the three sensor kinds ([`SensorFrame::parse`](crate::SensorFrame::parse)):
//! a kind-1 frame decodes with the EGI channels marked invalid, a kind-1 or kind-3 frame without
//! sub-samples. Frames of versions 1 to 5 are refused as `Error::Version(v)`, like any other
//! version (their headers do not name an aircraft).

pub mod estimate;
pub mod sensor;

/// Wire format version carried in every header (the table in the module docs).
pub const VERSION: u8 = 6;
/// Frame delimiter.
pub const DELIMITER: u8 = 0;
/// Header length.
pub const HEADER_LEN: usize = 12;
/// CRC length.
pub const CRC_LEN: usize = 4;
/// Longest body (header + payload) of any frame kind.
pub const MAX_BODY: usize = HEADER_LEN + sensor::EGI120_PAYLOAD_LEN;
/// Longest encoded frame including the delimiter.
pub const MAX_FRAME: usize = cobs::max_encoding_length(MAX_BODY + CRC_LEN) + 1;

const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// The tag of the aircraft description `name` in a frame header: the CRC-32 of the name.
pub const fn aircraft_tag(name: &str) -> u32 {
    CRC.checksum(name.as_bytes())
}

/// The tag of this build's aircraft ([`crate::aircraft::AIRCRAFT`]): every frame it sends carries
/// it, and it takes no frame without it.
pub const AIRCRAFT_TAG: u32 = aircraft_tag(crate::aircraft::AIRCRAFT.name);

/// Byte offsets of the header.
pub(crate) mod field {
    use core::ops::Range;
    pub const VERSION: usize = 0;
    pub const KIND: usize = 1;
    pub const SEQ: Range<usize> = 2..4;
    pub const TIME: Range<usize> = 4..8;
    pub const AIRCRAFT: Range<usize> = 8..12;
}

/// Why a frame was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// Fewer bytes than the frame kind needs.
    Truncated,
    /// More bytes than the frame kind has.
    TooLong,
    /// The COBS stuffing is broken.
    Cobs,
    /// The CRC does not match: bits were corrupted.
    Crc,
    /// A wire format version this build does not speak.
    Version(u8),
    /// The header names another frame kind.
    Kind(u8),
    /// The header names another aircraft (its [`aircraft_tag`]).
    Aircraft(u32),
    /// The output buffer is too small.
    Buffer,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Truncated => f.write_str("frame shorter than its kind"),
            Error::TooLong => f.write_str("frame longer than its kind"),
            Error::Cobs => f.write_str("broken COBS stuffing"),
            Error::Crc => f.write_str("CRC mismatch"),
            Error::Version(v) => write!(
                f,
                "wire format version {v}, but this build speaks version {VERSION}"
            ),
            Error::Kind(k) => write!(f, "unexpected frame kind {k}"),
            Error::Aircraft(t) => write!(
                f,
                "frame of another aircraft (tag {t:#010x}); this build is for {} (tag {AIRCRAFT_TAG:#010x})",
                crate::aircraft::AIRCRAFT.name
            ),
            Error::Buffer => f.write_str("output buffer too small"),
        }
    }
}

/// Frame kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Kind {
    /// A sensor frame of the Table 1 suite ([`crate::Suite::Table1`]).
    Sensor = 1,
    Estimate = 2,
    /// A sensor frame of the EGI suite ([`crate::Suite::Egi`]).
    SensorEgi = 3,
    /// A sensor frame of the EGI suite with the 120 Hz sub-samples ([`crate::Suite::Egi120`]).
    SensorEgi120 = 4,
}

/// The header fields common to every frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    pub kind: Kind,
    pub seq: u16,
    pub time_ms: u32,
}

pub(crate) fn read_u16(b: &[u8], at: core::ops::Range<usize>) -> u16 {
    b.get(at)
        .and_then(|s| <[u8; 2]>::try_from(s).ok())
        .map_or(0, u16::from_le_bytes)
}

pub(crate) fn read_u32(b: &[u8], at: core::ops::Range<usize>) -> u32 {
    b.get(at)
        .and_then(|s| <[u8; 4]>::try_from(s).ok())
        .map_or(0, u32::from_le_bytes)
}

pub(crate) fn write(b: &mut [u8], at: core::ops::Range<usize>, v: &[u8]) {
    if let Some(d) = b.get_mut(at) {
        for (d, s) in d.iter_mut().zip(v) {
            *d = *s;
        }
    }
}

/// Checks the header of a body of `kind` with a payload of `payload_len` bytes.
pub(crate) fn check_header(body: &[u8], kind: Kind, payload_len: usize) -> Result<(), Error> {
    // Another version's layout is unknown here, so its length proves nothing: a body naming another
    // version is refused as such before its length is judged. Versions start at 1; a zero byte names
    // none (garbage), and such a body is judged by its length first.
    let version = body.get(field::VERSION).copied().unwrap_or(0);
    if version != 0 && version != VERSION {
        return Err(Error::Version(version));
    }
    let want = HEADER_LEN.saturating_add(payload_len);
    match body.len() {
        n if n < want => return Err(Error::Truncated),
        n if n > want => return Err(Error::TooLong),
        _ => {}
    }
    if version != VERSION {
        return Err(Error::Version(version));
    }
    let k = body.get(field::KIND).copied().unwrap_or(0);
    if k != kind as u8 {
        return Err(Error::Kind(k));
    }
    let tag = read_u32(body, field::AIRCRAFT);
    if tag != AIRCRAFT_TAG {
        return Err(Error::Aircraft(tag));
    }
    Ok(())
}

pub(crate) fn header_of(body: &[u8]) -> (u16, u32) {
    (read_u16(body, field::SEQ), read_u32(body, field::TIME))
}

pub(crate) fn emit_header(body: &mut [u8], kind: Kind, seq: u16, time_ms: u32) {
    write(body, field::VERSION..field::VERSION + 1, &[VERSION]);
    write(body, field::KIND..field::KIND + 1, &[kind as u8]);
    write(body, field::SEQ, &seq.to_le_bytes());
    write(body, field::TIME, &time_ms.to_le_bytes());
    write(body, field::AIRCRAFT, &AIRCRAFT_TAG.to_le_bytes());
}

/// Appends the CRC to `body`, COBS-encodes it and the delimiter into `out`. Returns the encoded length.
pub fn encode(body: &[u8], out: &mut [u8]) -> Result<usize, Error> {
    let mut buf = [0u8; MAX_BODY + CRC_LEN];
    let n = body.len();
    // A saturated length is out of the buffer's range: `Buffer`, as for any body too long.
    let framed = buf
        .get_mut(..n.saturating_add(CRC_LEN))
        .ok_or(Error::Buffer)?;
    let (b, c) = framed.split_at_mut(n);
    b.copy_from_slice(body);
    c.copy_from_slice(&CRC.checksum(body).to_le_bytes());
    let len = cobs::try_encode(framed, out).map_err(|_| Error::Buffer)?;
    let d = out.get_mut(len).ok_or(Error::Buffer)?;
    *d = DELIMITER;
    // `out[len]` exists, so `len + 1 <= out.len()`: the add cannot saturate.
    Ok(len.saturating_add(1))
}

/// Decodes one COBS frame (without its delimiter) into `out` and checks its CRC. Returns the body.
pub fn decode<'o>(encoded: &[u8], out: &'o mut [u8]) -> Result<&'o [u8], Error> {
    if encoded.is_empty() {
        return Err(Error::Truncated);
    }
    let n = cobs::decode(encoded, out)
        .map_err(|_| Error::Cobs)?
        .frame_size();
    let framed = out.get(..n).ok_or(Error::Cobs)?;
    if n < HEADER_LEN + CRC_LEN {
        return Err(Error::Truncated);
    }
    let (body, crc) = framed
        .split_last_chunk::<CRC_LEN>()
        .ok_or(Error::Truncated)?;
    if u32::from_le_bytes(*crc) != CRC.checksum(body) {
        return Err(Error::Crc);
    }
    Ok(body)
}

/// Collects bytes off a stream into frames. `N` bounds the encoded frame; longer runs without a
/// delimiter are garbage and are dropped up to the next delimiter.
pub struct Accumulator<const N: usize> {
    buf: [u8; N],
    len: usize,
    overflow: bool,
    out: [u8; N],
}

impl<const N: usize> Default for Accumulator<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Accumulator<N> {
    pub const fn new() -> Self {
        Accumulator {
            buf: [0; N],
            len: 0,
            overflow: false,
            out: [0; N],
        }
    }

    /// Feeds one byte. At a delimiter, returns the decoded, CRC-checked body of the frame it ends, or
    /// why it was rejected. Empty frames (two delimiters in a row) are skipped silently.
    pub fn push(&mut self, byte: u8) -> Option<Result<&[u8], Error>> {
        if byte != DELIMITER {
            match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    // `buf[len]` exists, so `len < N`: the add cannot saturate.
                    self.len = self.len.saturating_add(1);
                }
                None => self.overflow = true,
            }
            return None;
        }
        let (len, overflow) = (self.len, self.overflow);
        self.len = 0;
        self.overflow = false;
        if overflow {
            return Some(Err(Error::TooLong));
        }
        if len == 0 {
            return None;
        }
        let encoded = self.buf.get(..len).unwrap_or(&[]);
        Some(decode(encoded, &mut self.out))
    }

    /// Drops a partial frame (e.g. after a receiver overrun).
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflow = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channels::{ALL_VALID, CHANNELS, SensorFrame, Suite};
    use proptest::prelude::*;

    fn frame(seq: u16) -> SensorFrame {
        let mut raw = [0i32; CHANNELS];
        for (i, r) in raw.iter_mut().enumerate() {
            *r = (i as i32 - 8) * 1000 + (seq % 1000) as i32;
        }
        raw[crate::Channel::Throttle.index()] = 5000;
        raw[crate::Channel::Fuel.index()] = 31_000;
        SensorFrame {
            seq,
            time_ms: seq as u32 * 50,
            raw,
            valid: ALL_VALID,
            sub: crate::channels::Subsamples::NONE,
        }
    }

    #[test]
    fn sensor_frames_of_both_suites_round_trip_through_the_stream() {
        for suite in Suite::ALL {
            let mut acc = Accumulator::<MAX_FRAME>::new();
            let mut got = 0;
            for seq in [0u16, 1, 255, 256, 65535] {
                let mut wire = [0u8; MAX_FRAME];
                let n = frame(seq).encode(suite, &mut wire).unwrap();
                assert!(!wire[..n - 1].contains(&0));
                for b in &wire[..n] {
                    if let Some(r) = acc.push(*b) {
                        assert_eq!(
                            SensorFrame::parse(r.unwrap()).unwrap(),
                            frame(seq).restricted_to(suite)
                        );
                        got += 1;
                    }
                }
            }
            assert_eq!(got, 5);
        }
    }

    #[test]
    fn every_single_bit_flip_is_rejected() {
        for suite in Suite::ALL {
            let mut wire = [0u8; MAX_FRAME];
            let n = frame(42).encode(suite, &mut wire).unwrap();
            for bit in 0..(n - 1) * 8 {
                let mut w = wire;
                w[bit / 8] ^= 1 << (bit % 8);
                let mut acc = Accumulator::<MAX_FRAME>::new();
                let mut accepted = 0;
                for b in &w[..n] {
                    if let Some(Ok(body)) = acc.push(*b)
                        && SensorFrame::parse(body).is_ok()
                    {
                        accepted += 1;
                    }
                }
                assert_eq!(
                    accepted, 0,
                    "{suite:?}: bit {bit} flipped and still accepted"
                );
            }
        }
    }

    #[test]
    fn a_version_2_frame_is_refused_naming_its_version() {
        // Version 2 had the kind-1 layout of today: the same bytes with version 2 in the header,
        // CRC and COBS intact, are refused as version 2, never read as a sensor frame.
        for suite in Suite::ALL {
            let mut body = [0u8; MAX_BODY];
            let n = frame(7)
                .emit_body(suite, &mut body)
                .expect("a sensor body fits MAX_BODY");
            body[field::VERSION] = 2;
            let mut wire = [0u8; MAX_FRAME];
            let len = encode(&body[..n], &mut wire).unwrap();
            let mut acc = Accumulator::<MAX_FRAME>::new();
            let mut results = std::vec::Vec::new();
            for b in &wire[..len] {
                if let Some(r) = acc.push(*b) {
                    results.push(r.and_then(SensorFrame::parse));
                }
            }
            assert_eq!(results, [Err(Error::Version(2))]);
            let text = std::format!("{}", Error::Version(2));
            assert!(
                text.contains("version 2") && text.contains("version 6"),
                "{text}"
            );
        }
    }

    #[test]
    fn a_frame_of_another_aircraft_is_refused_naming_its_tag() {
        // The same bytes with another description's tag, CRC and COBS intact: refused, for every
        // suite, never read as this aircraft's sensor frame.
        let other = aircraft_tag("another-aircraft");
        assert_ne!(other, AIRCRAFT_TAG);
        for suite in Suite::ALL {
            let mut body = [0u8; MAX_BODY];
            let n = frame(7)
                .emit_body(suite, &mut body)
                .expect("a sensor body fits MAX_BODY");
            assert_eq!(&body[field::AIRCRAFT], &AIRCRAFT_TAG.to_le_bytes());
            body[field::AIRCRAFT].copy_from_slice(&other.to_le_bytes());
            let mut wire = [0u8; MAX_FRAME];
            let len = encode(&body[..n], &mut wire).unwrap();
            let mut acc = Accumulator::<MAX_FRAME>::new();
            let got: std::vec::Vec<_> = wire[..len]
                .iter()
                .filter_map(|b| acc.push(*b).map(|r| r.and_then(SensorFrame::parse)))
                .collect();
            assert_eq!(got, [Err(Error::Aircraft(other))]);
        }
        let text = std::format!("{}", Error::Aircraft(other));
        assert!(
            text.contains(crate::aircraft::AIRCRAFT.name) && text.contains("another aircraft"),
            "{text}"
        );
    }

    #[test]
    fn the_tag_is_the_crc32_of_the_name() {
        // CRC-32/ISO-HDLC check value.
        assert_eq!(aircraft_tag("123456789"), 0xCBF4_3926);
        // The default aircraft's, as the module docs give it (every description's against
        // docs/architecture.md: tests/tests/aircraft.rs).
        assert_eq!(aircraft_tag("f16"), 0xBAFC_FCAB);
    }

    #[test]
    fn resynchronises_after_garbage_within_one_frame() {
        let mut acc = Accumulator::<MAX_FRAME>::new();
        let garbage = [0x13u8; 500];
        let mut wire = [0u8; MAX_FRAME];
        let n = frame(9).encode(Suite::Egi, &mut wire).unwrap();
        let mut results = std::vec::Vec::new();
        for b in garbage.iter().chain(&[0u8]).chain(&wire[..n]) {
            if let Some(r) = acc.push(*b) {
                results.push(r.map(SensorFrame::parse));
            }
        }
        assert_eq!(results.len(), 2);
        assert_eq!(results[0], Err(Error::TooLong));
        assert_eq!(results[1], Ok(Ok(frame(9))));
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            let mut acc = Accumulator::<MAX_FRAME>::new();
            for b in &bytes {
                if let Some(Ok(body)) = acc.push(*b) {
                    let _ = SensorFrame::parse(body);
                    let _ = estimate::EstimateFrame::parse(body);
                }
            }
            let mut out = [0u8; 512];
            let _ = decode(&bytes, &mut out);
        }
    }
}
