//! Scripted sensor faults: what a flight's frames look like when a sensor drops out, freezes or
//! clips, for a stretch of the flight. Applied to the frames after the sensor models and before
//! the link (`sensors → faults → frames → link`), so the firmware sees exactly what a faulty
//! sensor would send.
//!
//! Written on the command line as `KIND[:CHANNEL]@START+DURATION` (seconds of flight time):
//! * `gps-loss@300+30`: the GPS receiver has no fix: GPS speed and altitude are invalid. The EGI
//!   keeps its (inertially coasted) attitude and velocity; its error over 30 s of coasting is below
//!   the EGI error model's (`docs/sensors.md`), so its channels are left as they are.
//! * `dead:accel_y_mps2@100+10`: the channel's own built-in test fails: it is sent invalid.
//! * `stuck:gyro_r_rps@100+10`: the channel repeats its last value before the fault, still marked
//!   valid (nothing in the frame says it is wrong).
//! * `saturated:accel_z_mps2@100+0.5`: an IMU channel reads its clip level ([`Channel::full_scale`],
//!   sign of the value before the fault), still marked valid (a shock beyond the sensor's range).
//! * `bias:accel_z_mps2=-39.2@100+10`: the channel reads its true value plus a constant, in its
//!   unit, still marked valid: a bias shift, the failure nothing in the frame reveals (an IMU
//!   channel clips at its full scale).
//!
//! Channel names are the dataset column names ([`Channel::name`]).

use std::fmt;
use std::str::FromStr;

use estimator_core::channels::Subsamples;
use estimator_core::{Channel, SensorFrame};

/// What goes wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaultKind {
    GpsLoss,
    Dead(Channel),
    Stuck(Channel),
    Saturated(Channel),
    /// The channel plus this many of its LSBs.
    Bias(Channel, i32),
}

impl FaultKind {
    /// The channels the fault touches.
    pub fn channels(self) -> u32 {
        match self {
            FaultKind::GpsLoss => Channel::GpsSpeed.bit() | Channel::GpsAlt.bit(),
            FaultKind::Dead(c)
            | FaultKind::Stuck(c)
            | FaultKind::Saturated(c)
            | FaultKind::Bias(c, _) => c.bit(),
        }
    }
}

/// One fault over a stretch of flight time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fault {
    pub kind: FaultKind,
    pub start_s: f64,
    pub duration_s: f64,
}

impl Fault {
    /// Whether a frame at `time_s` is inside the fault.
    pub fn active(&self, time_s: f64) -> bool {
        time_s >= self.start_s && time_s < self.start_s + self.duration_s
    }
}

/// Why a fault text does not parse.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum FaultError {
    #[error(
        "fault `{0}`: write KIND[:CHANNEL]@START+DURATION in seconds, e.g. gps-loss@300+30, stuck:gyro_r_rps@100+10 or bias:accel_z_mps2=-39.2@100+10"
    )]
    Syntax(String),
    #[error("fault `{0}`: kinds are gps-loss, dead, stuck, saturated, bias")]
    Kind(String),
    #[error(
        "fault `{0}`: a bias is written bias:CHANNEL=VALUE, VALUE a finite number in the channel's unit that its frame field can hold"
    )]
    BiasValue(String),
    #[error(
        "fault `{0}`: unknown channel `{1}`; channels are the dataset column names, e.g. accel_y_mps2"
    )]
    Channel(String, String),
    #[error("fault `{0}`: only IMU channels (gyro_*, accel_*) have a full scale to saturate at")]
    NoFullScale(String),
    #[error("fault `{0}`: start must be >= 0 and duration > 0 seconds")]
    Window(String),
}

impl FromStr for Fault {
    type Err = FaultError;

    fn from_str(s: &str) -> Result<Fault, FaultError> {
        let syntax = || FaultError::Syntax(s.to_string());
        let (what, window) = s.split_once('@').ok_or_else(syntax)?;
        let (start, duration) = window.split_once('+').ok_or_else(syntax)?;
        let num = |v: &str| v.trim().parse::<f64>().map_err(|_| syntax());
        let (start_s, duration_s) = (num(start)?, num(duration)?);
        if !(start_s.is_finite() && start_s >= 0.0 && duration_s.is_finite() && duration_s > 0.0) {
            return Err(FaultError::Window(s.to_string()));
        }
        let (kind, chan) = match what.split_once(':') {
            Some((k, c)) => (k.trim(), Some(c.trim())),
            None => (what.trim(), None),
        };
        // A bias carries its size after the channel: `bias:CHANNEL=VALUE`.
        let (chan, value) = match chan.map(|c| c.split_once('=')) {
            Some(Some((c, v))) => (Some(c.trim()), Some(v.trim())),
            _ => (chan, None),
        };
        if value.is_some() != (kind == "bias") {
            return Err(if kind == "bias" {
                FaultError::BiasValue(s.to_string())
            } else {
                syntax()
            });
        }
        let channel = || -> Result<Channel, FaultError> {
            let c = chan.ok_or_else(syntax)?;
            Channel::ALL
                .into_iter()
                .find(|ch| ch.name() == c)
                .ok_or_else(|| FaultError::Channel(s.to_string(), c.to_string()))
        };
        let kind = match kind {
            "gps-loss" if chan.is_none() => FaultKind::GpsLoss,
            "gps-loss" => return Err(syntax()),
            "dead" => FaultKind::Dead(channel()?),
            "stuck" => FaultKind::Stuck(channel()?),
            "saturated" => {
                let c = channel()?;
                if c.full_scale().is_none() {
                    return Err(FaultError::NoFullScale(s.to_string()));
                }
                FaultKind::Saturated(c)
            }
            "bias" => {
                let c = channel()?;
                let bad = || FaultError::BiasValue(s.to_string());
                let v: f64 = value.ok_or_else(bad)?.parse().map_err(|_| bad())?;
                let raw = (v / c.lsb()).round();
                if !(raw.is_finite() && raw.abs() <= f64::from(i32::MAX)) {
                    return Err(bad());
                }
                FaultKind::Bias(c, raw as i32)
            }
            _ => return Err(FaultError::Kind(s.to_string())),
        };
        Ok(Fault {
            kind,
            start_s,
            duration_s,
        })
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            FaultKind::GpsLoss => write!(f, "gps-loss")?,
            FaultKind::Dead(c) => write!(f, "dead:{}", c.name())?,
            FaultKind::Stuck(c) => write!(f, "stuck:{}", c.name())?,
            FaultKind::Saturated(c) => write!(f, "saturated:{}", c.name())?,
            FaultKind::Bias(c, raw) => {
                // As many decimals as the LSB has: the value prints back as written.
                let decimals = (-c.lsb().log10()).ceil().max(0.0) as usize;
                let v = format!("{:.*}", decimals, f64::from(raw) * c.lsb());
                let v = if v.contains('.') {
                    v.trim_end_matches('0').trim_end_matches('.')
                } else {
                    &v
                };
                write!(f, "bias:{}={v}", c.name())?
            }
        }
        write!(f, "@{}+{}", self.start_s, self.duration_s)
    }
}

/// Applies `faults` to a flight's frames, `times_s` being each frame's flight time. A stuck or
/// saturated channel takes its value (or sign) from the last frame before its fault. A faulted
/// channel's 120 Hz sub-samples fail with it: invalid when it is dead, all six at its stuck or
/// saturated value, each offset by a bias (an IMU channel's within its full scale).
pub fn apply(faults: &[Fault], frames: &mut [SensorFrame], times_s: &[f64]) {
    for fault in faults {
        let mut before: Option<i32> = None;
        for (f, &t) in frames.iter_mut().zip(times_s) {
            let active = fault.active(t);
            match fault.kind {
                FaultKind::GpsLoss | FaultKind::Dead(_) if active => {
                    f.valid &= !fault.kind.channels();
                    f.sub.valid &= !Subsamples::mask_of(fault.kind.channels());
                }
                FaultKind::Stuck(c) if active => {
                    let v = *before.get_or_insert(f.get(c));
                    f.set_everywhere(c, v);
                }
                FaultKind::Saturated(c) if active => {
                    let sign = if before.unwrap_or(f.get(c)) < 0 {
                        -1
                    } else {
                        1
                    };
                    f.set_everywhere(c, sign * c.full_scale().unwrap_or(i32::MAX));
                    f.valid |= c.bit();
                }
                FaultKind::Bias(c, raw) if active => {
                    let limit = c.full_scale().unwrap_or(i32::MAX);
                    f.map_everywhere(c, |v| v.saturating_add(raw).clamp(-limit, limit));
                }
                FaultKind::Stuck(c) | FaultKind::Saturated(c) => before = Some(f.get(c)),
                _ => {}
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::channels::ALL_VALID;

    fn frames(n: usize) -> (Vec<SensorFrame>, Vec<f64>) {
        let f = (0..n)
            .map(|k| {
                let mut f = SensorFrame {
                    seq: k as u16,
                    time_ms: 50 * k as u32,
                    valid: ALL_VALID,
                    ..SensorFrame::default()
                };
                for (i, r) in f.raw.iter_mut().enumerate() {
                    *r = 100 * i as i32 - 5 * k as i32;
                }
                for (j, sample) in f.sub.raw.iter_mut().enumerate() {
                    for (i, r) in sample.iter_mut().enumerate() {
                        *r = 1000 * i as i32 + j as i32 - 5 * k as i32;
                    }
                }
                f.sub.valid = Subsamples::ALL_VALID;
                f
            })
            .collect();
        (f, (0..n).map(|k| k as f64 * 0.05).collect())
    }

    #[test]
    fn parses_and_prints_back() {
        for s in [
            "gps-loss@300+30",
            "dead:accel_y_mps2@100+10",
            "stuck:gyro_r_rps@1.5+2",
            "saturated:accel_z_mps2@100+0.5",
            "bias:accel_z_mps2=-39.2266@60+10",
            "bias:gyro_r_rps=0.01@60+10",
            "bias:rudder_deg=2@5+1",
        ] {
            assert_eq!(s.parse::<Fault>().map(|f| f.to_string()), Ok(s.to_string()));
        }
    }

    #[test]
    fn bad_texts_name_what_is_wrong() {
        let e = |s: &str| s.parse::<Fault>().unwrap_err();
        assert!(matches!(e("gps-loss"), FaultError::Syntax(_)));
        assert!(matches!(
            e("gps-loss:gyro_p_rps@1+1"),
            FaultError::Syntax(_)
        ));
        assert!(matches!(e("melted:gyro_p_rps@1+1"), FaultError::Kind(_)));
        assert!(matches!(e("dead:pitot@1+1"), FaultError::Channel(_, c) if c == "pitot"));
        assert!(matches!(
            e("saturated:rudder_deg@1+1"),
            FaultError::NoFullScale(_)
        ));
        assert!(matches!(e("dead:rudder_deg@1+0"), FaultError::Window(_)));
        assert!(matches!(e("dead:rudder_deg@-1+1"), FaultError::Window(_)));
        assert!(matches!(e("dead:rudder_deg@x+1"), FaultError::Syntax(_)));
        assert!(matches!(e("bias:rudder_deg@1+1"), FaultError::BiasValue(_)));
        assert!(matches!(
            e("bias:rudder_deg=x@1+1"),
            FaultError::BiasValue(_)
        ));
        assert!(matches!(
            e("bias:rudder_deg=inf@1+1"),
            FaultError::BiasValue(_)
        ));
        assert!(matches!(
            e("bias:gyro_p_rps=1e9@1+1"),
            FaultError::BiasValue(_)
        ));
        assert!(matches!(e("dead:rudder_deg=2@1+1"), FaultError::Syntax(_)));
        assert!(matches!(e("bias:pitot=2@1+1"), FaultError::Channel(_, c) if c == "pitot"));
    }

    #[test]
    fn each_kind_changes_only_its_channels_inside_its_window() {
        let (clean, t) = frames(100);
        for (text, c) in [
            ("gps-loss@1+2", Channel::GpsAlt),
            ("dead:accel_y_mps2@1+2", Channel::AccelY),
            ("stuck:gyro_r_rps@1+2", Channel::GyroR),
            ("saturated:accel_z_mps2@1+2", Channel::AccelZ),
            ("bias:rudder_deg=2@1+2", Channel::Rudder),
        ] {
            let fault: Fault = text.parse().unwrap();
            let mut f = clean.clone();
            apply(&[fault], &mut f, &t);
            for (k, (a, b)) in f.iter().zip(&clean).enumerate() {
                let inside = (20..60).contains(&k);
                let other = !fault.kind.channels();
                assert_eq!(a.valid & other, b.valid & other, "{text} {k}");
                for o in Channel::ALL.iter().filter(|o| o.bit() & other != 0) {
                    assert_eq!(a.get(*o), b.get(*o));
                }
                if !inside {
                    assert_eq!(a, b, "{text} {k}");
                    continue;
                }
                match fault.kind {
                    FaultKind::GpsLoss => assert!(!a.is_valid(c)),
                    FaultKind::Dead(_) => {
                        assert!(!a.is_valid(c) && !a.sub.is_valid(c));
                        assert!(a.sub.is_valid(Channel::AccelZ));
                    }
                    FaultKind::Stuck(_) => {
                        assert!(a.is_valid(c));
                        assert_eq!(a.get(c), clean[19].get(c));
                        assert!((0..6).all(|k| a.sub.get(k, c) == clean[19].get(c)));
                    }
                    FaultKind::Saturated(_) => {
                        assert!(a.is_valid(c));
                        let sign = clean[19].get(c).signum();
                        assert_eq!(a.get(c), sign * c.full_scale().unwrap());
                    }
                    FaultKind::Bias(_, raw) => {
                        assert!(a.is_valid(c));
                        assert_eq!(a.get(c), b.get(c) + raw);
                        assert!((0..6).all(|k| a.sub.get(k, c) == b.sub.get(k, c) + raw));
                    }
                }
            }
        }
    }
}
