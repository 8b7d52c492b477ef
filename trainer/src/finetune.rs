//! Fine-tuning a trained model on flight-test data: the networks of `trainer train` trained
//! further on the frames of a flight test, their targets the nose boom's air data, never the
//! simulator's truth (docs/calibration.md, "Fine-tuning the networks on the flight test").
//!
//! The boom's readings become targets in three steps:
//! 1. **The vanes' and the probe's lag undone.** Each channel reads through a first-order lag of a
//!    known time constant (the instrument's, recorded in the dataset's `config.boom`), applied at
//!    the 20 Hz samples: `y_k = a·y_{k−1} + (1 − a)·x_k` with `a = exp(−Δt/τ)`, so
//!    `x_k = (y_k − a·y_{k−1}) / (1 − a)` exactly, at the price of the noise growing by
//!    `√(1 + a²)/(1 − a)` (1.7 for the vanes' 0.05 s, 3.0 for the probe's 0.1 s).
//! 2. **The data-compatibility check's corrections** (`calibrate::boom_correction`): the
//!    rotation-induced flow at the boom removed, the vanes' gains and per-flight offsets and the
//!    airspeed's scale and per-flight bias applied.
//! 3. **The intermediate targets** of the cascades from the corrected air data: the body-axis
//!    vertical and lateral air velocities `w = V·sin α·cos β`, `v = V·sin β`.
//!
//! The frames are cut into blocks of [`BLOCK_S`]; every [`VAL_EVERY`]-th block is held out, and the
//! epoch whose held-out loss is lowest is kept (the model as it was, where no epoch beats it). The
//! model keeps its normalisation and envelopes; the int8 form is quantized again from the flight
//! test's frames.
use crate::calibrate::{BoomCorrection, boom_correction, boom_flights, boom_setting};
use crate::data::{Flight, Role, Target};
use crate::error::{Error, Result};
use crate::model::{Cascade, Curves, FloatLayer, Matrix, TrainConfig, train, val_losses};
use crate::quant::{QCascade, quantize_cascade};
use crate::saved::FloatCascade;
use burn::tensor::Device;
use estimator_core::filter::{self, CONFIG, Input};
use estimator_core::{FeatureState, SensorFrame};
use std::collections::BTreeMap;
use std::path::Path;

/// Length of the blocks the flight test is cut into, s.
pub const BLOCK_S: f64 = 30.0;
/// Every this many blocks, one (the middle one of each run) is held out for validation.
pub const VAL_EVERY: usize = 5;
/// Frames slower than this by the corrected boom are left out, m/s (as the data-compatibility
/// check leaves out frames slower than this by the EGI).
const MIN_TAS_MPS: f64 = 30.0;

/// The lag a first-order filter of time constant `tau_s` at steps of `dt_s` puts on a sampled
/// signal undone: `x_k = (y_k − a·y_{k−1}) / (1 − a)`, `a = exp(−dt/τ)`; the first sample is
/// taken as settled. A zero time constant leaves the signal as it is.
pub fn unlag(y: &[f64], tau_s: f64, dt_s: f64) -> Vec<f64> {
    if tau_s <= 0.0 {
        return y.to_vec();
    }
    let a = (-dt_s / tau_s).exp();
    let mut prev = None;
    y.iter()
        .map(|&yk| {
            let x = match prev {
                Some(p) => (yk - a * p) / (1.0 - a),
                None => yk,
            };
            prev = Some(yk);
            x
        })
        .collect()
}

/// A flight test's frames as flights whose targets are the corrected boom's air data, cut into
/// training and held-out blocks.
pub struct BoomFlights {
    pub train: Vec<Flight>,
    pub val: Vec<Flight>,
    /// The data-compatibility check the targets were corrected with.
    pub correction: BoomCorrection,
    /// Frames left out (the first of each flight, an invalid frame, under [`MIN_TAS_MPS`]).
    pub skipped: usize,
}

/// Reads the flight test in `dir`: every flight with a boom record, its frames' features as the
/// estimator computes them in flight, and the boom's corrected air data as the targets. The
/// flights' truth columns are never read.
pub fn boom_targets(dir: &Path) -> Result<BoomFlights> {
    let m = hil_sim::dataset::Manifest::read(dir)?;
    let correction = boom_correction(dir)?;
    let dt = 1.0 / f64::from(hil_sim::flight::SAMPLE_HZ);
    let lag =
        |channel: &str, default: f64| boom_setting(&m, &[channel, "lag_s"]).unwrap_or(default);
    let d = hil_sim::boom::BoomConfig::default();
    let taus = [
        lag("alpha", d.alpha.lag_s),
        lag("beta", d.beta.lag_s),
        lag("tas", d.tas.lag_s),
    ];
    let (mut train, mut val, mut skipped) = (Vec::new(), Vec::new(), 0);
    for (k, (e, csv, boom)) in boom_flights(dir, &m)?.into_iter().enumerate() {
        let channels: [Vec<f64>; 3] = [
            boom.iter().map(|b| b.alpha_deg).collect(),
            boom.iter().map(|b| b.beta_deg).collect(),
            boom.iter().map(|b| b.tas_mps).collect(),
        ];
        let [a, b, v] = [0, 1, 2].map(|i| unlag(&channels[i], taus[i], dt));
        let frames: Vec<SensorFrame> = hil_sim::frames::flight_frames(&csv).collect();
        let mut state = FeatureState::new(true);
        let t0 = csv.samples.first().map_or(0.0, |s| s.time_s);
        let mut blocks: BTreeMap<usize, Flight> = BTreeMap::new();
        for (i, (frame, sample)) in frames.iter().zip(&csv.samples).enumerate() {
            // Every frame goes through the features, in order, as in flight.
            let features = state.next(frame);
            let label = (i > 0)
                .then(|| Input::from_frame(frame, dt as f32, CONFIG.lever_arm_m, CONFIG.subsamples))
                .flatten()
                .and_then(|inp| {
                    let boom = [a.get(i).copied()?, b.get(i).copied()?, v.get(i).copied()?];
                    // The rotation-induced flow is divided by the corrected airspeed.
                    let v_arm = correction.air(k, boom, 0.0, 0.0, 1.0)[2].max(1.0);
                    let [alpha, beta, tas] = correction.air(
                        k,
                        boom,
                        f64::from(inp.gyro_rps[1]),
                        f64::from(inp.gyro_rps[2]),
                        v_arm,
                    );
                    (tas >= MIN_TAS_MPS && alpha.is_finite() && beta.is_finite()).then_some((
                        alpha,
                        beta,
                        tas,
                        filter::isa(inp.alt_m).0,
                    ))
                });
            let Some((alpha, beta, tas, rho)) = label else {
                skipped += 1;
                continue;
            };
            let block = ((sample.time_s - t0) / BLOCK_S).max(0.0) as usize;
            let fl = blocks.entry(block).or_insert_with(|| Flight {
                name: format!("{}#{block}", e.name),
                role: if block % VAL_EVERY == VAL_EVERY / 2 {
                    Role::Val
                } else {
                    Role::Train
                },
                time_s: Vec::new(),
                frames: Vec::new(),
                features: Vec::new(),
                truth: Default::default(),
                qbar_pa: Vec::new(),
                gyro_bias_twin: false,
            });
            // `truth` holds the targets, here the corrected boom's air data (and `qbar_pa` the
            // dynamic pressure at it and the ISA density), not the simulator's.
            let (ar, br) = (alpha.to_radians(), beta.to_radians());
            let targets = [
                (Target::AlphaDeg, alpha),
                (Target::BetaDeg, beta),
                (Target::WAero, tas * ar.sin() * br.cos()),
                (Target::VAero, tas * br.sin()),
            ];
            for (t, value) in targets {
                fl.truth[t as usize].push(value);
            }
            fl.qbar_pa.push(0.5 * f64::from(rho) * tas * tas);
            fl.time_s.push(sample.time_s);
            fl.frames.push(*frame);
            fl.features.push(features);
        }
        for fl in blocks.into_values() {
            match fl.role {
                Role::Val => val.push(fl),
                _ => train.push(fl),
            }
        }
    }
    if train.is_empty() || val.is_empty() {
        return Err(Error::Split(
            dir.to_path_buf(),
            format!(
                "too few frames with boom air data above {MIN_TAS_MPS} m/s: every {VAL_EVERY}th block of {BLOCK_S} s is held out, so a flight needs more than {} s above that speed; fly the card of `hil-sim generate --preset flight-test`",
                BLOCK_S * (VAL_EVERY / 2 + 1) as f64
            ),
        ));
    }
    Ok(BoomFlights {
        train,
        val,
        correction,
        skipped,
    })
}

/// One cascade fine-tuned.
pub struct Tuned {
    pub part1: Vec<FloatLayer>,
    pub part2: Vec<FloatLayer>,
    pub q: QCascade,
    pub curves: Curves,
    /// The held-out blocks' loss `[intermediate, angle]` of the model as it was.
    pub val_before: [f64; 2],
    /// Whether an epoch beat the model as it was on the held-out blocks (else it is kept).
    pub improved: bool,
    /// Int8 MAE against the boom on the held-out blocks, before and after, deg.
    pub val_mae_deg: [f64; 2],
}

/// Int8 MAE of a cascade against the boom's targets on `flights`, deg.
fn boom_mae(q: &QCascade, flights: &[&Flight]) -> f64 {
    let target = q.prep.angle.target();
    let (mut sum, mut n) = (0.0, 0usize);
    for fl in flights {
        for (v, want) in fl.features.iter().zip(fl.truth(target)) {
            sum += (f64::from(q.reference(v).angle) / 1000.0 - want).abs();
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

/// What a fine-tuning trains, and on what besides the flight test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tune {
    /// Every parameter.
    All,
    /// Part 2's output layer alone.
    Output,
}

/// Rows of `flights` (simulated training flights, their truth the targets) evenly spread, at most
/// `rows` of them, in `prep`'s scaling.
fn replay_matrix(prep: &crate::prep::Prep, flights: &[&Flight], rows: usize) -> Matrix {
    let (mut x, mut ym, mut yo) = (Vec::new(), Vec::new(), Vec::new());
    for (fl, i) in crate::data::spread_rows(flights, rows) {
        let (Some(m), Some(o)) = (
            fl.truth(prep.angle.intermediate()).get(i),
            fl.truth(prep.angle.target()).get(i),
        ) else {
            continue;
        };
        prep.input(&fl.features[i], &mut x);
        ym.push(prep.mid_z(*m));
        yo.push(prep.out_z(*o));
    }
    Matrix {
        x,
        ym,
        yo,
        n_in: prep.n_inputs(),
    }
}

/// Trains `f` further on the training blocks of `data` (`cfg`: epochs, learning rate, batch,
/// seed, loss) and, with `replay`, as many rows of those simulated flights again, so that what
/// the flight test does not fly is not forgotten; keeps the epoch of the lowest held-out loss if
/// it beats the model as it was, and quantizes it with the model's normalisation.
pub fn finetune(
    f: &FloatCascade,
    data: &BoomFlights,
    replay: &[&Flight],
    tune: Tune,
    cfg: &TrainConfig,
) -> Tuned {
    let prep = &f.q.prep;
    let tr: Vec<&Flight> = data.train.iter().collect();
    let va: Vec<&Flight> = data.val.iter().collect();
    let (mut train_m, val_m): (Matrix, Matrix) = (prep.matrix(&tr), prep.matrix(&va));
    if !replay.is_empty() {
        let r = replay_matrix(prep, replay, train_m.rows());
        train_m.x.extend(r.x);
        train_m.ym.extend(r.ym);
        train_m.yo.extend(r.yo);
    }
    let before = Cascade::from_layers(&f.part1, &f.part2, &Device::flex());
    let val_before = val_losses(&before, &val_m, cfg.loss);
    let (model, curves) = train(
        |d| {
            let c = Cascade::from_layers(&f.part1, &f.part2, d);
            match tune {
                Tune::All => c,
                Tune::Output => c.output_layer_only(),
            }
        },
        cfg,
        &train_m,
        &val_m,
    );
    let best = curves
        .val
        .get(curves.best_epoch)
        .map_or(f64::INFINITY, |v| v[0] + v[1]);
    let improved = best < val_before[0] + val_before[1];
    let (part1, part2, q) = if improved {
        let (part1, part2) = (model.part1.export(), model.part2.export());
        // The activation scales from the flight test's frames and the replayed ones.
        let mut calib = crate::pipeline::calibration(prep, &tr, 20_000);
        calib.extend(crate::pipeline::calibration(prep, replay, 20_000));
        let q = quantize_cascade(prep, &part1, &part2, &calib);
        (part1, part2, q)
    } else {
        (f.part1.clone(), f.part2.clone(), f.q.clone())
    };
    let val_mae_deg = [boom_mae(&f.q, &va), boom_mae(&q, &va)];
    Tuned {
        part1,
        part2,
        q,
        curves,
        val_before,
        improved,
        val_mae_deg,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boom's lag (`hil_sim::boom`: exact discretisation at the samples) undone gives the
    /// signal back.
    #[test]
    fn unlag_inverts_the_first_order_lag_at_the_samples() {
        let (tau, dt): (f64, f64) = (0.05, 0.05);
        let a = (-dt / tau).exp();
        let x: Vec<f64> = (0..200)
            .map(|k| (k as f64 * 0.3).sin() * 5.0 + if k > 80 { 2.0 } else { 0.0 })
            .collect();
        let mut y = Vec::new();
        for (k, xk) in x.iter().enumerate() {
            let prev = if k == 0 { *xk } else { y[k - 1] };
            y.push(if k == 0 {
                *xk
            } else {
                a * prev + (1.0 - a) * xk
            });
        }
        let back = unlag(&y, tau, dt);
        for (got, want) in back.iter().zip(&x) {
            assert!((got - want).abs() < 1e-12, "{got} against {want}");
        }
        assert_eq!(unlag(&y, 0.0, dt), y);
    }
}
