//! The model-based air-data filter ([`estimator_core::filter`]) scored on a dataset's flights, on the
//! target's own path: each flight's integer sensor frames, in order, through
//! [`AirDataFilter::step_frame`], exactly as the firmware runs it.
use estimator_core::filter::{AirDataFilter, Config, Output, flags};

use crate::data::{Dataset, Role, Target};
use crate::metrics::FlightMetrics;

/// Per-flight share of frames with each flag raised.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct FlagShare {
    pub flight: String,
    pub frames: usize,
    pub no_input: f64,
    pub gated: f64,
    pub restarted: usize,
    pub low_confidence: f64,
    /// Mean 1σ of α and β the filter reported, degrees (to set beside the measured error).
    pub mean_sigma_alpha_deg: f64,
    pub mean_sigma_beta_deg: f64,
    /// The lift, side-force and trailing-edge lift scales the filter had learned at the flight's
    /// last frame (the last 0 where the filter does not learn it).
    pub final_lift_scale: f64,
    pub final_side_scale: f64,
    pub final_te_lift: f64,
    /// The filter's gain error in β on this flight ([`gain_error`]).
    pub beta_gain_error: f64,
}

/// What [`eval_filter`] measures.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct FilterEval {
    /// Every frame, flagged or not (the honest figure).
    pub alpha: FlightMetrics,
    pub beta: FlightMetrics,
    /// Only the frames with no flag raised.
    pub alpha_trusted: FlightMetrics,
    pub beta_trusted: FlightMetrics,
    pub flags: Vec<FlagShare>,
    /// The filter's gain error in β over every frame of the flights ([`gain_error`]).
    pub beta_gain_error: f64,
}

/// The gain error of an estimate: the least-squares slope (with an intercept) of its error over
/// the truth, −0.05 reading a true 4° as 3.8°. NaN when the two differ in length or the truth has
/// no spread beyond rounding.
pub fn gain_error(estimate: &[f64], truth: &[f64]) -> f64 {
    if estimate.len() != truth.len() || truth.is_empty() {
        return f64::NAN;
    }
    let n = truth.len() as f64;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
    let (mt, me) = (mean(truth), mean(estimate));
    let (mut cov, mut var) = (0.0, 0.0);
    for (e, t) in estimate.iter().zip(truth) {
        cov += (t - mt) * ((e - t) - (me - mt));
        var += (t - mt) * (t - mt);
    }
    // A constant truth leaves only the rounding of its mean: about ε² · mean² per sample.
    let floor = n * (f64::EPSILON * mt.abs().max(1.0)).powi(2) * 1e4;
    if var > floor { cov / var } else { f64::NAN }
}

/// Runs one flight; the outputs, one per frame.
pub fn run_flight(cfg: Config, frames: &[estimator_core::SensorFrame]) -> Vec<Output> {
    let mut f = AirDataFilter::new(cfg);
    let mut prev_ms: Option<u32> = None;
    frames
        .iter()
        .map(|fr| {
            let dt = prev_ms.map_or(0.05, |p| fr.time_ms.wrapping_sub(p) as f32 / 1000.0);
            prev_ms = Some(fr.time_ms);
            f.step_frame(fr, dt)
        })
        .collect()
}

/// The filter's α and β in degrees, one per output.
pub fn degrees(out: &[Output]) -> (Vec<f64>, Vec<f64>) {
    out.iter()
        .map(|o| {
            (
                f64::from(o.alpha_rad).to_degrees(),
                f64::from(o.beta_rad).to_degrees(),
            )
        })
        .unzip()
}

/// The filter with `cfg` on every flight of `role`.
pub fn eval_filter(ds: &Dataset, role: Role, cfg: Config) -> FilterEval {
    let (mut a, mut b, mut at, mut bt, mut shares) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for fl in ds.flights(role) {
        let out = run_flight(cfg, &fl.frames);
        let ta = fl.truth(Target::AlphaDeg);
        let tb = fl.truth(Target::BetaDeg);
        let (pa, pb) = degrees(&out);
        let ok: Vec<bool> = out.iter().map(|o| flags::clear(o.flags)).collect();
        let keep = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .zip(&ok)
                .filter(|(_, k)| **k)
                .map(|(x, _)| *x)
                .collect()
        };
        at.push((fl.name.clone(), keep(&pa), keep(ta)));
        bt.push((fl.name.clone(), keep(&pb), keep(tb)));
        let beta_gain_error = gain_error(&pb, tb);
        a.push((fl.name.clone(), pa, ta.to_vec()));
        b.push((fl.name.clone(), pb, tb.to_vec()));
        let n = out.len().max(1) as f64;
        let share = |bit: u8| out.iter().filter(|o| o.flags & bit != 0).count() as f64 / n;
        shares.push(FlagShare {
            flight: fl.name.clone(),
            frames: out.len(),
            no_input: share(flags::NO_INPUT),
            gated: share(flags::GATED),
            restarted: out
                .iter()
                .filter(|o| o.flags & flags::RESTARTED != 0)
                .count(),
            low_confidence: share(flags::LOW_CONFIDENCE),
            mean_sigma_alpha_deg: out
                .iter()
                .map(|o| f64::from(o.sigma_alpha_rad).to_degrees())
                .sum::<f64>()
                / n,
            mean_sigma_beta_deg: out
                .iter()
                .map(|o| f64::from(o.sigma_beta_rad).to_degrees())
                .sum::<f64>()
                / n,
            final_lift_scale: out.last().map_or(f64::NAN, |o| f64::from(o.lift_scale)),
            final_side_scale: out.last().map_or(f64::NAN, |o| f64::from(o.side_scale)),
            final_te_lift: out.last().map_or(f64::NAN, |o| f64::from(o.te_lift)),
            beta_gain_error,
        });
    }
    // Every frame of every flight, for the pooled gain.
    let (every_b, every_tb): (Vec<f64>, Vec<f64>) = b
        .iter()
        .flat_map(|(_, p, t)| p.iter().copied().zip(t.iter().copied()))
        .unzip();
    FilterEval {
        alpha: FlightMetrics::of(&a),
        beta: FlightMetrics::of(&b),
        alpha_trusted: FlightMetrics::of(&at),
        beta_trusted: FlightMetrics::of(&bt),
        flags: shares,
        beta_gain_error: gain_error(&every_b, &every_tb),
    }
}

#[cfg(test)]
mod tests {
    use super::gain_error;

    #[test]
    fn a_gain_error_is_the_slope_of_the_error_over_the_truth() {
        let truth = [-4.0, -1.0, 0.0, 2.0, 5.0];
        // 5 % low with an offset of 0.1°: the offset is not a gain.
        let low: Vec<f64> = truth.iter().map(|t| 0.95 * t + 0.1).collect();
        assert!((gain_error(&low, &truth) + 0.05).abs() < 1e-12);
        assert!(gain_error(&truth, &truth).abs() < 1e-12);
        assert!(gain_error(&[1.0, 2.0], &[3.0, 3.0]).is_nan());
        // A constant truth whose mean does not round exactly.
        assert!(gain_error(&[0.2, 0.1, 0.0], &[0.1, 0.1, 0.1]).is_nan());
        assert!(gain_error(&[], &[]).is_nan());
        assert!(gain_error(&[1.0], &[1.0, 2.0]).is_nan());
    }
}
