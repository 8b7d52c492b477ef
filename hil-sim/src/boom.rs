//! The flight-test nose boom: α and β vanes and a pitot-static probe on a boom ahead of the nose,
//! as a flight-test aircraft carries for calibration (NASA TM-104316, Haering; Parameswaran,
//! Jategaonkar & Press 2005). Recorded only in `flight-test` datasets, beside each flight's CSV as
//! `NAME.boom.csv`; never a channel of a sensor frame, so never an input of the estimator.
//!
//! Each channel, at the 20 Hz samples (docs/sensors.md, "Flight-test nose boom"):
//! the local flow at the boom (α − q·x/V, β + r·x/V: the boom is x ahead of the CG), times one plus
//! the installation's calibration residual (the part of the upwash/sidewash or position-error
//! calibration that is left), plus a per-flight misalignment bias, through a first-order lag, plus
//! white noise, quantized to the resolution.
//!
//! Beside the boom, the record carries engine 0's instrumentation (a turbine's core speed N2 or a
//! propeller's speed, and the throttle position, through the same error model): flight-test
//! calibration computes the thrust from them with the engine deck, to tell the drag from the
//! thrust along body x. The flight-test card moves every engine's throttle together, so engine 0
//! stands for all.

#[cfg(feature = "sim")]
use rand::SeedableRng;
#[cfg(feature = "sim")]
use rand_chacha::ChaCha12Rng;
#[cfg(feature = "sim")]
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

#[cfg(feature = "sim")]
use crate::flight::{Flight, SAMPLE_HZ};

/// One boom channel's error model (`Default`: an ideal channel).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ChannelErrors {
    /// White noise, 1σ (channel units).
    pub noise: f64,
    /// Quantization step (channel units).
    pub resolution: f64,
    /// First-order lag time constant, s (vane dynamics, pneumatic lag).
    pub lag_s: f64,
    /// Calibration residual: the measurement is the local value times (1 + this).
    pub scale_residual: f64,
    /// Misalignment / zero shift, 1σ of a per-flight constant (channel units).
    pub bias_sigma: f64,
}

/// The boom's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoomConfig {
    /// How far ahead of the CG the vanes are, m.
    pub arm_m: f64,
    /// α vane, degrees.
    pub alpha: ChannelErrors,
    /// β vane, degrees.
    pub beta: ChannelErrors,
    /// True airspeed from the pitot-static probe, m/s.
    pub tas: ChannelErrors,
    /// Engine 0's core speed N2, %.
    pub n2: ChannelErrors,
    /// Engine 0's throttle position (JSBSim's norm: 1 military power, 2 full afterburner).
    pub throttle: ChannelErrors,
    /// Engine 0's propeller speed, rpm.
    pub propeller_rpm: ChannelErrors,
}

impl Default for BoomConfig {
    fn default() -> Self {
        let vane = ChannelErrors {
            noise: 0.05,
            resolution: 0.02,
            lag_s: 0.05,
            scale_residual: 0.01,
            bias_sigma: 0.1,
        };
        BoomConfig {
            arm_m: estimator_core::aircraft::AIRCRAFT.installation.boom_arm_m,
            alpha: vane,
            beta: vane,
            tas: ChannelErrors {
                noise: 0.3,
                resolution: 0.1,
                lag_s: 0.1,
                scale_residual: 0.005,
                bias_sigma: 0.5,
            },
            // A core-speed indication to 0.1 % with a per-flight zero shift of 0.1 % (about 0.5 %
            // of the thrust near military power).
            n2: ChannelErrors {
                noise: 0.05,
                resolution: 0.1,
                lag_s: 0.0,
                scale_residual: 0.0,
                bias_sigma: 0.1,
            },
            throttle: ChannelErrors {
                resolution: 0.001,
                ..ChannelErrors::default()
            },
            // A flight-test tachometer to 1 rpm with a per-flight calibration error of 5 rpm
            // (about 0.6 % of a fixed-pitch propeller's thrust at 2,400 rpm and J 0.7: n² and
            // C_T(J) both move with it).
            propeller_rpm: ChannelErrors {
                noise: 2.0,
                resolution: 1.0,
                lag_s: 0.0,
                scale_residual: 0.0,
                bias_sigma: 5.0,
            },
        }
    }
}

/// One boom sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoomSample {
    pub time_s: f64,
    pub alpha_deg: f64,
    pub beta_deg: f64,
    pub tas_mps: f64,
    /// Engine 0's core speed, % (`None`, an empty cell, for an engine without one, or a record
    /// without the engine channels), and throttle position (`None` without the engine channels).
    pub engine_n2_pct: Option<f64>,
    pub engine_throttle_pos: Option<f64>,
    /// Engine 0's propeller speed, rpm (`None` for an engine without a propeller, or a record
    /// without the column).
    pub engine_propeller_rpm: Option<f64>,
}

/// The columns from here on are the engine's, optional in a record read.
const ENGINE_COLUMNS: usize = 4;

/// The CSV header of `NAME.boom.csv`.
pub const COLUMNS: [&str; 7] = [
    "time_s",
    "boom_alpha_deg",
    "boom_beta_deg",
    "boom_tas_mps",
    "engine_n2_pct",
    "engine_throttle_pos",
    "engine_propeller_rpm",
];

#[cfg(feature = "sim")]
struct Channel {
    e: ChannelErrors,
    bias: f64,
    a: f64,
    state: Option<f64>,
}

#[cfg(feature = "sim")]
impl Channel {
    fn new(e: ChannelErrors, rng: &mut ChaCha12Rng) -> Channel {
        let z: f64 = StandardNormal.sample(rng);
        let dt = 1.0 / f64::from(SAMPLE_HZ);
        Channel {
            e,
            bias: e.bias_sigma * z,
            a: if e.lag_s > 0.0 {
                (-dt / e.lag_s).exp()
            } else {
                0.0
            },
            state: None,
        }
    }

    fn step(&mut self, local: f64, rng: &mut ChaCha12Rng) -> f64 {
        let x = local * (1.0 + self.e.scale_residual) + self.bias;
        let y = match self.state {
            Some(s) => self.a * s + (1.0 - self.a) * x,
            None => x,
        };
        self.state = Some(y);
        let n: f64 = StandardNormal.sample(rng);
        crate::sensors::quantize(y + self.e.noise * n, self.e.resolution)
    }
}

/// What the boom recorded over `flight` (one sample per flight sample), for sensor seed `seed`.
#[cfg(feature = "sim")]
pub fn record(flight: &Flight, cfg: &BoomConfig, seed: u64) -> Vec<BoomSample> {
    let mut rng = ChaCha12Rng::seed_from_u64(seed ^ 0x626f_6f6d_2d76_616e);
    let mut alpha = Channel::new(cfg.alpha, &mut rng);
    let mut beta = Channel::new(cfg.beta, &mut rng);
    let mut tas = Channel::new(cfg.tas, &mut rng);
    // The engine's channels draw from their own stream: the boom's are the same with or without.
    let mut engine_rng = ChaCha12Rng::seed_from_u64(seed ^ 0x656e_6769_6e65_2d6e);
    let mut n2 = Channel::new(cfg.n2, &mut engine_rng);
    let mut throttle = Channel::new(cfg.throttle, &mut engine_rng);
    let mut propeller = Channel::new(cfg.propeller_rpm, &mut engine_rng);
    // A flight without its engine state at every sample (one read back from its CSV) records none.
    let engine = (flight.engine.len() == flight.samples.len()).then_some(&flight.engine);
    flight
        .samples
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let t = &s.truth;
            let v = t.vt_mps.max(1.0);
            let local_alpha = t.alpha_deg - (t.q_true_rps * cfg.arm_m / v).to_degrees();
            let local_beta = t.beta_deg + (t.r_true_rps * cfg.arm_m / v).to_degrees();
            let engine = engine.and_then(|e| e.get(k));
            BoomSample {
                time_s: s.time_s,
                alpha_deg: alpha.step(local_alpha, &mut rng),
                beta_deg: beta.step(local_beta, &mut rng),
                tas_mps: tas.step(t.vt_mps, &mut rng),
                engine_n2_pct: engine
                    .and_then(|e| e.n2_pct)
                    .map(|x| n2.step(x, &mut engine_rng)),
                engine_throttle_pos: engine.map(|e| throttle.step(e.throttle_pos, &mut engine_rng)),
                engine_propeller_rpm: engine
                    .and_then(|e| e.propeller_rpm)
                    .map(|x| propeller.step(x, &mut engine_rng)),
            }
        })
        .collect()
}

/// Writes `samples` as CSV bytes.
pub fn write_csv<W: std::io::Write>(w: W, samples: &[BoomSample]) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    wr.write_record(COLUMNS)?;
    for s in samples {
        wr.write_record([
            s.time_s.to_string(),
            s.alpha_deg.to_string(),
            s.beta_deg.to_string(),
            s.tas_mps.to_string(),
            s.engine_n2_pct.map_or_else(String::new, |x| x.to_string()),
            s.engine_throttle_pos
                .map_or_else(String::new, |x| x.to_string()),
            s.engine_propeller_rpm
                .map_or_else(String::new, |x| x.to_string()),
        ])?;
    }
    wr.flush()?;
    Ok(())
}

/// A `NAME.boom.csv` that does not read.
#[derive(Debug, thiserror::Error)]
pub enum BoomError {
    #[error("{path}: {message}")]
    Csv {
        path: std::path::PathBuf,
        message: String,
    },
    #[error("{path}: missing column `{column}` (is this a flight-test dataset's NAME.boom.csv?)")]
    MissingColumn {
        path: std::path::PathBuf,
        column: &'static str,
    },
}

/// Reads a `NAME.boom.csv` (columns by name).
pub fn read_csv(path: &std::path::Path) -> Result<Vec<BoomSample>, BoomError> {
    let err = |message: String| BoomError::Csv {
        path: path.to_path_buf(),
        message,
    };
    let mut rd = csv::Reader::from_path(path).map_err(|e| err(e.to_string()))?;
    let header = rd.headers().map_err(|e| err(e.to_string()))?.clone();
    // The engine channels are optional: a record made before them has the boom's alone, and
    // calibration then says the drag needs them.
    let idx: Vec<Option<usize>> = COLUMNS
        .iter()
        .enumerate()
        .map(|(i, c)| match header.iter().position(|h| h == *c) {
            Some(at) => Ok(Some(at)),
            None if i >= ENGINE_COLUMNS => Ok(None),
            None => Err(BoomError::MissingColumn {
                path: path.to_path_buf(),
                column: c,
            }),
        })
        .collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    for rec in rd.records() {
        let rec = rec.map_err(|e| err(e.to_string()))?;
        // An empty cell is a channel the aircraft does not have (a piston engine's N2, a
        // turbine's propeller speed).
        let v: Vec<Option<f64>> = idx
            .iter()
            .map(|&i| {
                let cell = i.and_then(|i| rec.get(i)).unwrap_or("").trim();
                (!cell.is_empty()).then(|| cell.parse::<f64>()).transpose()
            })
            .collect::<Result<_, _>>()
            .map_err(|e| err(format!("line {}: {e}", out.len() + 2)))?;
        let line = out.len() + 2;
        let need = |i: usize| {
            v.get(i)
                .copied()
                .flatten()
                .ok_or_else(|| err(format!("line {line}: `{}` is empty", COLUMNS[i])))
        };
        out.push(BoomSample {
            time_s: need(0)?,
            alpha_deg: need(1)?,
            beta_deg: need(2)?,
            tas_mps: need(3)?,
            engine_n2_pct: v.get(4).copied().flatten(),
            engine_throttle_pos: v.get(5).copied().flatten(),
            engine_propeller_rpm: v.get(6).copied().flatten(),
        });
    }
    Ok(out)
}

#[cfg(all(test, feature = "sim"))]
mod tests {
    use super::*;
    use crate::flight::{Sample, Truth};

    fn flight(n: usize, truth: impl Fn(usize) -> Truth) -> Flight {
        Flight {
            name: "t".into(),
            samples: (0..n)
                .map(|k| Sample {
                    time_s: k as f64 / 20.0,
                    truth: truth(k),
                    sensed: [0.0; estimator_core::CHANNELS],
                    sub: crate::flight::NO_SUBSAMPLES,
                })
                .collect(),
            cut: None,
            zones: None,
            engine: Vec::new(),
        }
    }

    fn quiet() -> BoomConfig {
        let c = ChannelErrors::default();
        BoomConfig {
            arm_m: 6.0,
            alpha: c,
            beta: c,
            tas: c,
            n2: c,
            throttle: c,
            propeller_rpm: c,
        }
    }

    #[test]
    fn an_ideal_boom_reads_the_local_flow_at_the_boom() {
        let f = flight(3, |_| Truth {
            alpha_deg: 5.0,
            beta_deg: 1.0,
            vt_mps: 200.0,
            q_true_rps: 0.1,
            r_true_rps: -0.05,
            ..Truth::default()
        });
        let b = record(&f, &quiet(), 1);
        // Pitching up, the nose sees the air from above: α − q·x/V; yawing left, β + r·x/V.
        assert!((b[2].alpha_deg - (5.0 - (0.1f64 * 6.0 / 200.0).to_degrees())).abs() < 1e-12);
        assert!((b[2].beta_deg - (1.0 + (-0.05f64 * 6.0 / 200.0).to_degrees())).abs() < 1e-12);
        assert_eq!(b[2].tas_mps, 200.0);
    }

    #[test]
    fn residual_lag_and_resolution_act_as_specified() {
        let mut cfg = quiet();
        cfg.alpha.scale_residual = 0.02;
        cfg.alpha.lag_s = 0.05;
        cfg.alpha.resolution = 0.02;
        // A step from 0 to 10° after the first sample.
        let f = flight(40, |k| Truth {
            alpha_deg: if k == 0 { 0.0 } else { 10.0 },
            vt_mps: 200.0,
            ..Truth::default()
        });
        let b = record(&f, &cfg, 1);
        let a = (-0.05f64 / 0.05).exp();
        // One sample after the step: the lag's first response, on the 0.02° grid.
        let want = (10.2 * (1.0 - a) / 0.02).round() * 0.02;
        assert!(
            (b[1].alpha_deg - want).abs() < 1e-9,
            "{} vs {want}",
            b[1].alpha_deg
        );
        // Settled: 10° × 1.02.
        assert!((b[39].alpha_deg - 10.2).abs() < 1e-9, "{}", b[39].alpha_deg);
        assert!(
            b.iter()
                .all(|s| ((s.alpha_deg / 0.02).round() * 0.02 - s.alpha_deg).abs() < 1e-9)
        );
    }

    #[test]
    fn the_same_seed_records_the_same_and_the_csv_round_trips() {
        let f = flight(50, |k| Truth {
            alpha_deg: k as f64 * 0.1,
            beta_deg: -0.5,
            vt_mps: 180.0,
            ..Truth::default()
        });
        let cfg = BoomConfig::default();
        let vanes = |r: &[BoomSample]| -> Vec<[f64; 4]> {
            r.iter()
                .map(|s| [s.time_s, s.alpha_deg, s.beta_deg, s.tas_mps])
                .collect()
        };
        let without_engine = record(&f, &cfg, 7);
        // An N2 on every other sample, a propeller speed on the others (None: the other kind of
        // engine's empty cell).
        let mut f = f;
        f.engine = (0..50)
            .map(|k| crate::flight::EngineState {
                n2_pct: (k % 2 == 0).then_some(90.0 + k as f64 * 0.01),
                throttle_pos: 0.8,
                propeller_rpm: (k % 2 == 1).then_some(2_400.0),
            })
            .collect();
        let (a, b) = (record(&f, &cfg, 7), record(&f, &cfg, 7));
        assert_eq!(a, b);
        // The engine's channels draw from their own stream: the boom's are the same.
        assert_eq!(vanes(&a), vanes(&without_engine));
        assert!(
            a.iter()
                .step_by(2)
                .all(|s| s.engine_n2_pct.is_some_and(|n| (n - 90.25).abs() < 1.0))
        );
        assert!(a.iter().skip(1).step_by(2).all(|s| {
            s.engine_n2_pct.is_none()
                && s.engine_propeller_rpm
                    .is_some_and(|n| (n - 2_400.0).abs() < 30.0 && n.fract() == 0.0)
        }));
        assert!(
            a.iter()
                .step_by(2)
                .all(|s| s.engine_propeller_rpm.is_none())
        );
        assert!(a.iter().all(|s| s.engine_throttle_pos == Some(0.8)));
        // Without the engine state at every sample, no engine channel.
        assert!(
            without_engine
                .iter()
                .all(|s| s.engine_n2_pct.is_none() && s.engine_throttle_pos.is_none())
        );
        assert_ne!(a, record(&f, &cfg, 8));
        let dir = std::env::temp_dir().join(format!("boom-{}.csv", std::process::id()));
        write_csv(std::fs::File::create(&dir).unwrap(), &a).unwrap();
        assert_eq!(read_csv(&dir).unwrap(), a);
        // A record made before the engine channels reads, without them; a boom column is needed.
        std::fs::write(
            &dir,
            "time_s,boom_alpha_deg,boom_beta_deg,boom_tas_mps\n0.05,2.5,0.1,150\n",
        )
        .unwrap();
        let old = read_csv(&dir).unwrap();
        assert_eq!(
            (
                old[0].tas_mps,
                old[0].engine_n2_pct,
                old[0].engine_throttle_pos,
                old[0].engine_propeller_rpm
            ),
            (150.0, None, None, None)
        );
        std::fs::write(&dir, "time_s,boom_alpha_deg,boom_beta_deg\n0.05,2.5,0.1\n").unwrap();
        assert!(matches!(
            read_csv(&dir),
            Err(BoomError::MissingColumn {
                column: "boom_tas_mps",
                ..
            })
        ));
        let _ = std::fs::remove_file(dir);
    }
}
