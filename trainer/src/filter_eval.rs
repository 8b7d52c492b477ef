//! The model-based air-data filter ([`estimator_core::filter`]) scored on a dataset's flights, on the
//! target's own path: each flight's integer sensor frames, in order, through
//! [`AirDataFilter::step_frame`], exactly as the firmware runs it.
use estimator_core::aero::{MODEL, Unsteady};
use estimator_core::filter::{self, AirDataFilter, Config, Input, Output, flags};
use hil_sim::dataset::Truth;
use hil_sim::flight::FT_TO_M;
use nalgebra::Vector3;

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

/// One frame of [`force_frames`]: the normal (body z) specific force at the CG as the IMU measures
/// it and as the filter's force model gives it, at the flight's true air-data point and at the
/// filter's own estimate. NaN where a value cannot be had (no input, the model undefined there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceFrame {
    pub alpha_true_deg: f64,
    pub qbar_pa: f64,
    pub alpha_filter_deg: f64,
    pub sigma_alpha_filter_deg: f64,
    /// The filter had no standing flag ([`flags::clear`]).
    pub filter_clear: bool,
    /// The IMU's specific force moved to the CG ([`filter::specific_force_cg`]), m/s².
    pub fz_measured: f64,
    /// The model at the true α, β, Mach, airspeed, dynamic pressure, mass and body rates (JSBSim's
    /// truth: what the model would say if the filter knew the air-data point), m/s².
    pub fz_model_true: f64,
    /// The model at the filter's α, β and airspeed (ISA density at the frame's altitude, the mass
    /// from the fuel gauge, times the filter's lift scale), m/s².
    pub fz_model_filter: f64,
    /// ∂(fz_model_filter)/∂α at the filter's point, m/s² per degree: what one degree of α does to
    /// the normal force there.
    pub dfz_dalpha_filter: f64,
}

impl ForceFrame {
    /// The CSV header of [`ForceFrame::csv_row`] (after the flight name and frame index).
    pub const CSV_HEADER: &str = "flight,frame,alpha_true_deg,qbar_pa,alpha_filter_deg,sigma_alpha_filter_deg,filter_clear,fz_measured_mps2,fz_model_true_mps2,fz_model_filter_mps2,dfz_dalpha_filter_mps2_per_deg";

    pub fn csv_row(&self, flight: &str, frame: usize) -> String {
        format!(
            "{flight},{frame},{:.5},{:.1},{:.5},{:.5},{},{:.5},{:.5},{:.5},{:.5}",
            self.alpha_true_deg,
            self.qbar_pa,
            self.alpha_filter_deg,
            self.sigma_alpha_filter_deg,
            u8::from(self.filter_clear),
            self.fz_measured,
            self.fz_model_true,
            self.fz_model_filter,
            self.dfz_dalpha_filter
        )
    }
}

/// The filter with `cfg` over a flight's `frames` (as [`run_flight`]) and, frame by frame, the
/// normal force it is given against the force its model makes at the true air-data point
/// (`truth`, one record per frame) and at its own estimate: whether the model explains what the
/// accelerometers measure, and how much of the filter's α error the normal force shows.
///
/// `frames` and `truth` are one flight's, one record per frame: lengths that differ are refused.
pub fn force_frames(
    cfg: Config,
    frames: &[estimator_core::SensorFrame],
    truth: &[Truth],
) -> crate::error::Result<Vec<ForceFrame>> {
    if frames.len() != truth.len() {
        return Err(crate::error::Error::TruthLength {
            frames: frames.len(),
            truth: truth.len(),
        });
    }
    let out = run_flight(cfg, frames);
    let s_m2 = f64::from(MODEL.wing_area_ft2) * FT_TO_M * FT_TO_M;
    // The previous frame's time and true α, and the previous valid input (none after an invalid
    // frame: the IMU's force is moved to the CG with the gyro change since it).
    let mut prev_frame: Option<(u32, f64)> = None;
    let mut prev: Option<Input> = None;
    let (mut latch_true, mut latch_filter) = (false, false);
    Ok(frames
        .iter()
        .zip(&out)
        .zip(truth)
        .map(|((fr, o), t)| {
            let nan = f64::NAN;
            let a_true = t.alpha_deg.to_radians();
            // The step as `run_flight` times it, and α̇ by the difference over it.
            let dt = prev_frame.map_or(0.05, |(ms, _)| fr.time_ms.wrapping_sub(ms) as f32 / 1000.0);
            let alpha_dot_true = match prev_frame {
                Some((ms, a)) if fr.time_ms > ms => {
                    (a_true - a) / (f64::from(fr.time_ms - ms) / 1000.0)
                }
                _ => 0.0,
            };
            prev_frame = Some((fr.time_ms, a_true));
            let inp = Input::from_frame(fr, dt, cfg.lever_arm_m, cfg.subsamples);
            latch_true = MODEL.stall_latch(latch_true, a_true as f32);
            let mut row = ForceFrame {
                alpha_true_deg: t.alpha_deg,
                qbar_pa: t.qbar_pa,
                alpha_filter_deg: f64::from(o.alpha_rad).to_degrees(),
                sigma_alpha_filter_deg: f64::from(o.sigma_alpha_rad).to_degrees(),
                filter_clear: flags::clear(o.flags),
                fz_measured: nan,
                fz_model_true: nan,
                fz_model_filter: nan,
                dfz_dalpha_filter: nan,
            };
            let (Some(inp), Some(p)) = (inp, prev) else {
                prev = inp;
                return row;
            };
            prev = Some(inp);
            let f_cg = filter::specific_force_cg(&inp, &p, cfg.lever_arm_m);
            row.fz_measured = f64::from(f_cg.z);
            // The model at the true point, in JSBSim's own dynamic pressure and mass.
            let unsteady = Unsteady {
                alpha_dot_rps: alpha_dot_true as f32,
                stall_latched: latch_true,
            };
            let rates = [t.p_true_rps, t.q_true_rps, t.r_true_rps].map(|r| r as f32);
            let at_true = filter::model_point(
                &inp,
                rates,
                a_true as f32,
                t.beta_deg.to_radians() as f32,
                t.mach as f32,
                t.vt_mps as f32,
                cfg.gear_norm,
                unsteady,
            );
            if let Some(pt) = at_true {
                let c = MODEL.coefficients_at(&pt);
                if c.valid {
                    row.fz_model_true = f64::from(c.body.z) * t.qbar_pa * s_m2 / t.mass_kg;
                }
            }
            // The model at the filter's point, as its update evaluates it.
            let (rho, a_sound) = filter::isa(inp.alt_m);
            let v = o.airspeed_mps;
            // The filter's body air velocity, as its output derives α, β and the airspeed.
            let cbn = filter::c_bn(inp.euler_rad);
            let vb = cbn * (Vector3::from(inp.vel_ned_mps) - Vector3::from(o.wind_ned_mps));
            latch_filter = MODEL.stall_latch(latch_filter, o.alpha_rad);
            let unsteady = Unsteady {
                alpha_dot_rps: filter::alpha_rate(&vb, &cbn, inp.vel_ned_mps, &f_cg, inp.gyro_rps),
                stall_latched: latch_filter,
            };
            let at_filter = filter::model_point(
                &inp,
                inp.gyro_rps,
                o.alpha_rad,
                o.beta_rad,
                v / a_sound,
                v,
                cfg.gear_norm,
                unsteady,
            );
            if let Some(pt) = at_filter.filter(|_| v > 1.0) {
                let c = MODEL.coefficients_at(&pt);
                if c.valid {
                    let qs = f64::from(
                        filter::qs_over_m(rho, v, cfg.mass_kg(inp.fuel_kg)) * o.lift_scale,
                    );
                    row.fz_model_filter = f64::from(c.body.z) * qs;
                    // Per radian to per degree.
                    row.dfz_dalpha_filter = (f64::from(c.body_d_alpha.z) * qs).to_radians();
                }
            }
            row
        })
        .collect())
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
