//! The simulated serial line between hil-sim and the firmware, one [`Direction`] each way.
//!
//! Each byte takes 10 bit times (8N1) at the configured baud rate; a transmission queues behind the
//! previous one, then arrives after a fixed latency plus jitter (kept in order: a UART does not
//! reorder). Faults, all per byte and independent except bursts: the byte is lost, each of its bits
//! flips, or a noise burst starts and replaces the next `burst_len` bytes with random ones. Every
//! draw comes from a ChaCha stream seeded per direction, so a run repeats exactly.

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha12Rng;
use serde::{Deserialize, Serialize};

/// One direction's line parameters (TOML keys are the field names).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LinkConfig {
    /// Line rate, bit/s (8N1: 10 bits per byte).
    pub baud: u32,
    /// Fixed delay added to every transmission, ms.
    pub latency_ms: f64,
    /// Uniform extra delay in [0, jitter_ms) per transmission, ms.
    pub jitter_ms: f64,
    /// Probability that a byte is lost.
    pub byte_loss: f64,
    /// Probability that each bit of a delivered byte is inverted.
    pub bit_flip: f64,
    /// Probability per byte that a noise burst starts.
    pub burst_rate: f64,
    /// Bytes a burst replaces with random values.
    pub burst_len: u32,
}

impl Default for LinkConfig {
    fn default() -> Self {
        LinkConfig {
            baud: 115_200,
            latency_ms: 0.0,
            jitter_ms: 0.0,
            byte_loss: 0.0,
            bit_flip: 0.0,
            burst_rate: 0.0,
            burst_len: 8,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    #[error("cannot read link configuration {path}: {source}")]
    Read {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("link configuration {path} is not valid TOML for a link: {source}")]
    Parse {
        path: std::path::PathBuf,
        source: toml::de::Error,
    },
    #[error("link parameter {name} = {value} is out of range ({expected})")]
    Range {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
}

impl LinkConfig {
    /// Reads a TOML file with any of the fields (the rest keep their defaults).
    pub fn load(path: &Path) -> Result<LinkConfig, LinkError> {
        let text = std::fs::read_to_string(path).map_err(|source| LinkError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let cfg: LinkConfig = toml::from_str(&text).map_err(|source| LinkError::Parse {
            path: path.to_path_buf(),
            source,
        })?;
        cfg.validate()?;
        Ok(cfg)
    }

    pub fn validate(&self) -> Result<(), LinkError> {
        let prob = |name, value: f64| {
            if (0.0..=1.0).contains(&value) {
                Ok(())
            } else {
                Err(LinkError::Range {
                    name,
                    value,
                    expected: "a probability in [0, 1]",
                })
            }
        };
        prob("byte_loss", self.byte_loss)?;
        prob("bit_flip", self.bit_flip)?;
        prob("burst_rate", self.burst_rate)?;
        let nonneg = |name, value: f64| {
            if value >= 0.0 && value.is_finite() {
                Ok(())
            } else {
                Err(LinkError::Range {
                    name,
                    value,
                    expected: "finite and ≥ 0",
                })
            }
        };
        nonneg("latency_ms", self.latency_ms)?;
        nonneg("jitter_ms", self.jitter_ms)?;
        if self.baud == 0 {
            return Err(LinkError::Range {
                name: "baud",
                value: 0.0,
                expected: "> 0",
            });
        }
        Ok(())
    }

    /// Seconds one byte occupies the line.
    pub fn byte_time_s(&self) -> f64 {
        10.0 / f64::from(self.baud.max(1))
    }
}

/// What a direction did to the bytes it carried.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LinkStats {
    pub bytes_sent: u64,
    pub bytes_delivered: u64,
    pub bytes_lost: u64,
    pub bits_flipped: u64,
    pub bursts: u64,
    pub bytes_in_bursts: u64,
    /// Transmissions (frames) that arrived with any byte lost or changed.
    pub frames_altered: u64,
    pub frames_sent: u64,
}

/// Bytes as they arrive at the far end.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Delivery {
    pub bytes: Vec<u8>,
    /// Arrival time of each byte, s (same clock as the send time).
    pub arrival_s: Vec<f64>,
    /// Whether any byte was lost or changed.
    pub altered: bool,
}

/// One direction of the line.
pub struct Direction {
    cfg: LinkConfig,
    rng: ChaCha12Rng,
    /// When the line is free again, s.
    free_at_s: f64,
    last_arrival_s: f64,
    burst_left: u32,
    stats: LinkStats,
}

impl Direction {
    pub fn new(cfg: LinkConfig, seed: u64) -> Direction {
        Direction {
            cfg,
            rng: ChaCha12Rng::seed_from_u64(seed),
            free_at_s: 0.0,
            last_arrival_s: 0.0,
            burst_left: 0,
            stats: LinkStats::default(),
        }
    }

    pub fn stats(&self) -> LinkStats {
        self.stats
    }

    /// Sends `bytes` as one transmission starting no earlier than `t_s`.
    pub fn transmit(&mut self, t_s: f64, bytes: &[u8]) -> Delivery {
        let byte_s = self.cfg.byte_time_s();
        let start = t_s.max(self.free_at_s);
        self.free_at_s = start + byte_s * bytes.len() as f64;
        let jitter = if self.cfg.jitter_ms > 0.0 {
            self.rng.random_range(0.0..self.cfg.jitter_ms)
        } else {
            0.0
        };
        let delay = (self.cfg.latency_ms + jitter) * 1e-3;
        let mut out = Delivery {
            bytes: Vec::with_capacity(bytes.len()),
            arrival_s: Vec::with_capacity(bytes.len()),
            altered: false,
        };
        for (i, &b) in bytes.iter().enumerate() {
            self.stats.bytes_sent += 1;
            let arrival = (start + byte_s * (i + 1) as f64 + delay).max(self.last_arrival_s);
            if self.burst_left == 0
                && self.cfg.burst_rate > 0.0
                && self.rng.random_bool(self.cfg.burst_rate)
            {
                self.burst_left = self.cfg.burst_len;
                self.stats.bursts += 1;
            }
            let mut byte = b;
            if self.burst_left > 0 {
                self.burst_left -= 1;
                self.stats.bytes_in_bursts += 1;
                byte = self.rng.random();
            }
            if self.cfg.byte_loss > 0.0 && self.rng.random_bool(self.cfg.byte_loss) {
                self.stats.bytes_lost += 1;
                out.altered = true;
                continue;
            }
            if self.cfg.bit_flip > 0.0 {
                for bit in 0..8 {
                    if self.rng.random_bool(self.cfg.bit_flip) {
                        byte ^= 1 << bit;
                        self.stats.bits_flipped += 1;
                    }
                }
            }
            out.altered |= byte != b;
            self.last_arrival_s = arrival;
            self.stats.bytes_delivered += 1;
            out.bytes.push(byte);
            out.arrival_s.push(arrival);
        }
        self.stats.frames_sent += 1;
        if out.altered {
            self.stats.frames_altered += 1;
        }
        out
    }
}

/// Both directions, seeded from one seed.
pub struct Link {
    /// hil-sim → firmware (sensor frames).
    pub up: Direction,
    /// firmware → hil-sim (estimate frames).
    pub down: Direction,
}

impl Link {
    pub fn new(cfg: &LinkConfig, seed: u64) -> Link {
        Link {
            up: Direction::new(cfg.clone(), seed),
            down: Direction::new(cfg.clone(), seed ^ 0x9E37_79B9_7F4A_7C15),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noisy() -> LinkConfig {
        LinkConfig {
            byte_loss: 0.01,
            bit_flip: 0.001,
            burst_rate: 0.001,
            jitter_ms: 2.0,
            ..LinkConfig::default()
        }
    }

    /// The link budget at the board's 115 200 Bd: the largest sensor frame (kind 4, with the
    /// 120 Hz sub-samples; COBS's worst case and the delimiter) once per 20 Hz period uses under
    /// 60 % of the line, and the estimate frames of the other direction about 10 %.
    #[test]
    fn every_frame_kind_fits_the_20_hz_period_at_115200_bd() {
        use estimator_core::wire::{MAX_FRAME, estimate, sensor};
        let frames_per_s = 1000.0 / f64::from(estimator_core::features::FRAME_PERIOD_MS);
        let per_s = |bytes: usize| bytes as f64 * 10.0 * frames_per_s;
        let baud = f64::from(LinkConfig::default().baud);
        assert_eq!(baud, 115_200.0);
        assert_eq!(sensor::EGI120_BODY_LEN, 320);
        // CRC, COBS (one byte per 254) and the delimiter.
        assert_eq!(MAX_FRAME, sensor::EGI120_BODY_LEN + 4 + 2 + 1);
        let share = per_s(MAX_FRAME) / baud;
        assert!(share < 0.6, "a kind-4 frame takes {share:.3} of the line");
        let estimate_frame = estimate::BODY_LEN + 4 + 3;
        assert!(per_s(estimate_frame) / baud < 0.12);
    }

    #[test]
    fn a_clean_line_delivers_every_byte_at_the_baud_rate() {
        let mut d = Direction::new(LinkConfig::default(), 1);
        let bytes: Vec<u8> = (0..=255).collect();
        let got = d.transmit(1.0, &bytes);
        assert_eq!(got.bytes, bytes);
        assert!(!got.altered);
        let byte_s = 10.0 / 115_200.0;
        assert!((got.arrival_s[0] - (1.0 + byte_s)).abs() < 1e-12);
        assert!((got.arrival_s[255] - (1.0 + 256.0 * byte_s)).abs() < 1e-9);
        // A second transmission queues behind the first.
        let next = d.transmit(1.0, &[7]);
        assert!((next.arrival_s[0] - (1.0 + 257.0 * byte_s)).abs() < 1e-9);
    }

    #[test]
    fn same_seed_same_faults_other_seed_other_faults() {
        let data: Vec<u8> = (0..20_000u32).map(|i| (i * 7) as u8).collect();
        let run = |seed| {
            let mut d = Direction::new(noisy(), seed);
            (d.transmit(0.0, &data), d.stats())
        };
        assert_eq!(run(5), run(5));
        assert_ne!(run(5).0.bytes, run(6).0.bytes);
    }

    #[test]
    fn fault_rates_match_their_parameters() {
        let cfg = LinkConfig {
            byte_loss: 0.01,
            bit_flip: 0.001,
            ..LinkConfig::default()
        };
        let mut d = Direction::new(cfg, 3);
        let n = 200_000;
        let got = d.transmit(0.0, &vec![0x55; n]);
        let s = d.stats();
        assert_eq!(s.bytes_sent, n as u64);
        assert_eq!(s.bytes_lost + s.bytes_delivered, n as u64);
        assert_eq!(got.bytes.len() as u64, s.bytes_delivered);
        // 2000 ± 5σ lost bytes, 1600 ± 5σ flipped bits.
        assert!((1780..2220).contains(&s.bytes_lost), "{s:?}");
        assert!((1400..1800).contains(&s.bits_flipped), "{s:?}");
        // Arrival times never go backwards, even with jitter.
        let mut j = Direction::new(noisy(), 9);
        let mut last = 0.0;
        for k in 0..100 {
            for t in j.transmit(k as f64 * 1e-3, &[1, 2, 3]).arrival_s {
                assert!(t >= last);
                last = t;
            }
        }
    }

    #[test]
    fn bursts_replace_whole_runs() {
        let cfg = LinkConfig {
            burst_rate: 0.01,
            burst_len: 16,
            ..LinkConfig::default()
        };
        let mut d = Direction::new(cfg, 11);
        d.transmit(0.0, &vec![0u8; 50_000]);
        let s = d.stats();
        assert!(s.bursts > 200, "{s:?}");
        assert_eq!(s.bytes_in_bursts, s.bursts * 16);
    }

    #[test]
    fn toml_overrides_only_what_it_names_and_rejects_nonsense() {
        let dir = std::env::temp_dir().join(format!("hil-link-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("link.toml");
        std::fs::write(&p, "byte_loss = 1e-3\nbaud = 921600\n").unwrap();
        let c = LinkConfig::load(&p).unwrap();
        assert_eq!(c.byte_loss, 1e-3);
        assert_eq!(c.baud, 921_600);
        assert_eq!(c.bit_flip, 0.0);
        std::fs::write(&p, "byte_loss = 2.0\n").unwrap();
        assert!(matches!(LinkConfig::load(&p), Err(LinkError::Range { .. })));
        std::fs::write(&p, "bytes_loss = 0.1\n").unwrap();
        assert!(matches!(LinkConfig::load(&p), Err(LinkError::Parse { .. })));
    }
}
