//! Post-training quantization (scheme: estimator-core/src/nn/mod.rs), an independent i64 integer
//! reference of the deployed network, the `weights.rs` code generator and the test-vector writer.
use crate::model::{FloatLayer, float_forward};
use crate::prep::{Angle, Prep, fixed_point, fp_value};
use estimator_core::channels::{ALL_VALID, SUB_CHANNEL_COUNT, SUBSAMPLES, SUBSAMPLES_VALID};
use estimator_core::normalize::{Envelope, Norm, ONE_SIGMA, TurbulenceEnvelope};
use estimator_core::{Channel, Feature, FeatureState, FeatureValues, SensorFrame, Suite};
use nalgebra::DMatrix;
use std::fmt::Write;

/// One quantized layer: `weights[o][i]` int8, bias in accumulator units, requant per output.
#[derive(Debug, Clone, PartialEq)]
pub struct QLayer {
    pub weights: Vec<Vec<i8>>,
    pub bias: Vec<i32>,
    /// `(mult, shift, offset)` per output.
    pub requant: Vec<(i32, u8, i32)>,
    pub hidden: bool,
}

impl QLayer {
    pub fn n_in(&self) -> usize {
        self.weights.first().map_or(0, |r| r.len())
    }
    pub fn n_out(&self) -> usize {
        self.weights.len()
    }
}

/// A quantized cascade for one angle.
#[derive(Debug, Clone)]
pub struct QCascade {
    pub prep: Prep,
    pub part1: Vec<QLayer>,
    pub part2: Vec<QLayer>,
}

/// Largest accumulator bias for a layer with `n_in` inputs (the check `Dense::new` applies).
pub fn bias_headroom(n_in: usize) -> i64 {
    i32::MAX as i64 - n_in as i64 * 32767 * 127
}

/// Headroom of a hidden layer's int16 scale over the largest |activation| of the calibration rows:
/// int16 has the resolution to spare (1/21845 of that largest value per step), and an activation
/// beyond it in flight saturates instead of wrapping. Measured on the c172p's validation flights,
/// int8 α / β MAE 0.081 / 0.138 with the 99.99th percentile (which clipped the rare largest
/// activations, those of the high-α and most turbulent frames), 0.079 / 0.134 with 1.5 × the
/// largest, 0.077 / 0.133 with that and GPTQ's rounding ([`round_rows`]).
pub const ACTIVATION_HEADROOM: f64 = 1.5;

/// Rounds each weight row of `l` to int8 at the row's scale (its largest |w| / 127), by the error
/// feedback of GPTQ (Frantar et al., 2023): weight by weight, the rounding error of one is moved
/// onto the later ones through the inverse of the inputs' second moment H = E[x xᵀ] over `inputs`,
/// which minimises E[((w − q)·x)²] instead of each |w − q| alone. It matters where one large
/// weight sets a row's scale and leaves the others a few steps. Returns (int8 row, scale) per row;
/// plain rounding when H cannot be inverted or there are no inputs.
fn round_rows(l: &FloatLayer, inputs: &[Vec<f32>]) -> Vec<(Vec<i8>, f64)> {
    let n = l.n_in();
    let scale = |row: &[f32]| {
        let m = row.iter().fold(0f32, |m, w| m.max(w.abs())) as f64;
        if m > 0.0 { m / 127.0 } else { 1.0 }
    };
    let q = |v: f64, s: f64| (v / s).round().clamp(-127.0, 127.0);
    // Upper Cholesky factor U of H⁻¹ (H⁻¹ = Uᵀ U), H damped by 1 % of its mean diagonal.
    let mut h = DMatrix::<f64>::zeros(n, n);
    for x in inputs {
        for i in 0..n {
            let xi = f64::from(x[i]);
            for j in i..n {
                h[(i, j)] += xi * f64::from(x[j]);
            }
        }
    }
    let count = inputs.len().max(1) as f64;
    let mean_diag = (0..n).map(|i| h[(i, i)]).sum::<f64>() / (n.max(1) as f64 * count);
    let damp = if mean_diag > 0.0 {
        0.01 * mean_diag
    } else {
        1.0
    };
    for i in 0..n {
        for j in i..n {
            h[(i, j)] /= count;
            h[(j, i)] = h[(i, j)];
        }
        h[(i, i)] += damp;
    }
    let u = (!inputs.is_empty())
        .then(|| h.cholesky())
        .flatten()
        .map(|c| c.inverse())
        .and_then(|hinv| hinv.cholesky())
        .map(|c| c.l().transpose());
    l.weights
        .iter()
        .map(|row| {
            let s = scale(row);
            let mut w: Vec<f64> = row.iter().map(|v| f64::from(*v)).collect();
            let mut out = Vec::with_capacity(n);
            for i in 0..n {
                let qi = q(w[i], s);
                if let Some(u) = &u {
                    let e = (w[i] - qi * s) / u[(i, i)];
                    for j in i + 1..n {
                        w[j] -= e * u[(i, j)];
                    }
                }
                out.push(qi as i8);
            }
            (out, s)
        })
        .collect()
}

/// Quantizes one MLP. `s_in` is the real value of one input step, `calib` the float inputs used to
/// calibrate the hidden activation scales ([`ACTIVATION_HEADROOM`] × the largest |activation| per
/// layer) and the weights' rounding ([`round_rows`]), and
/// `out_per_real` the output units per real output (mm/s or millidegrees per normalised unit) with
/// `offset` added after requantization.
pub fn quantize_mlp(
    layers: &[FloatLayer],
    s_in: f64,
    calib: &[Vec<f32>],
    out_per_real: f64,
    offset: i32,
) -> Vec<QLayer> {
    let n_hidden = layers.len().saturating_sub(1);
    // Each hidden layer's outputs on the calibration rows: the inputs of the layer after it.
    let mut hidden_out: Vec<Vec<Vec<f32>>> = vec![Vec::with_capacity(calib.len()); n_hidden];
    for x in calib {
        float_forward(layers, x, |k, y| hidden_out[k].push(y.to_vec()));
    }
    let scales: Vec<f64> = hidden_out
        .iter()
        .map(|rows| {
            let largest = rows.iter().flatten().fold(0f32, |m, a| m.max(a.abs()));
            let p = ACTIVATION_HEADROOM * f64::from(largest);
            if p > 0.0 { p / 32767.0 } else { 1.0 / 32767.0 }
        })
        .collect();
    let mut out = Vec::new();
    let mut s_x = s_in;
    for (k, l) in layers.iter().enumerate() {
        let hidden = k < n_hidden;
        let headroom = bias_headroom(l.n_in());
        let mut q = QLayer {
            weights: Vec::new(),
            bias: Vec::new(),
            requant: Vec::new(),
            hidden,
        };
        let inputs = match k.checked_sub(1) {
            Some(i) => &hidden_out[i][..],
            None => calib,
        };
        for ((row, s_w), b) in round_rows(l, inputs).into_iter().zip(&l.bias) {
            q.weights.push(row);
            let bq = (*b as f64 / (s_x * s_w))
                .round()
                .clamp(-headroom as f64, headroom as f64);
            q.bias.push(bq as i32);
            let ratio = if hidden {
                s_x * s_w / scales[k]
            } else {
                s_x * s_w * out_per_real
            };
            let (mult, shift) = fixed_point(ratio, i32::MAX as i64);
            q.requant
                .push((mult, shift, if hidden { 0 } else { offset }));
        }
        if hidden {
            s_x = scales[k];
        }
        out.push(q);
    }
    out
}

/// Quantizes a trained cascade. `calib` are float inputs (normalised) of training rows.
pub fn quantize_cascade(
    prep: &Prep,
    part1: &[FloatLayer],
    part2: &[FloatLayer],
    calib: &[Vec<f32>],
) -> QCascade {
    let s_in = 1.0 / ONE_SIGMA as f64;
    let mid_scale = fp_value(prep.mid_norm.mult, prep.mid_norm.shift) / ONE_SIGMA as f64;
    let q1 = quantize_mlp(part1, s_in, calib, 1.0 / mid_scale, prep.mid_norm.center);
    let calib2: Vec<Vec<f32>> = calib
        .iter()
        .map(|x| {
            let mut v = x.clone();
            v.push(float_forward(part1, x, |_, _| {}));
            v
        })
        .collect();
    let q2 = quantize_mlp(part2, s_in, &calib2, prep.out_sigma, prep.out_center);
    QCascade {
        prep: prep.clone(),
        part1: q1,
        part2: q2,
    }
}

// ---------------------------------------------------------------------------------------------
// Independent integer reference (i64), written from the documented scheme, not from the layers.

fn ref_norm(center: i32, mult: i32, shift: u8, raw: i64) -> i64 {
    let s = (shift as u32).clamp(1, 62);
    let v = ((raw - center as i64) * mult as i64 + (1i64 << (s - 1))) >> s;
    v.clamp(-32768, 32767)
}

fn ref_layer(l: &QLayer, x: &[i64]) -> Vec<i64> {
    l.weights
        .iter()
        .zip(&l.bias)
        .zip(&l.requant)
        .map(|((row, b), (mult, shift, offset))| {
            let mut acc = *b as i64;
            for (w, xi) in row.iter().zip(x) {
                acc += *w as i64 * xi;
            }
            // The target accumulates in i32 with wrapping adds; by construction it never wraps.
            let acc = acc as i32 as i64;
            let s = (*shift as u32).clamp(1, 62);
            let y = ((acc * *mult as i64 + (1i64 << (s - 1))) >> s) + *offset as i64;
            if l.hidden {
                y.clamp(0, 32767)
            } else {
                y.clamp(i32::MIN as i64, i32::MAX as i64)
            }
        })
        .collect()
}

fn ref_mlp(layers: &[QLayer], x: Vec<i64>) -> i64 {
    layers
        .iter()
        .fold(x, |x, l| ref_layer(l, &x))
        .first()
        .copied()
        .unwrap_or(0)
}

/// Result of the integer reference for one angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RefOut {
    /// Intermediate, mm/s.
    pub mid: i32,
    /// Angle, millidegrees.
    pub angle: i32,
    /// A feature or the output was clamped to the training envelope (or GPS speed too low).
    pub clamped: bool,
}

impl QCascade {
    /// The deployed integer network on one frame's features.
    pub fn reference(&self, v: &FeatureValues) -> RefOut {
        let p = &self.prep;
        let mut clamped = false;
        let mut x = Vec::with_capacity(p.features.len() + 1);
        for ((f, n), e) in p.features.iter().zip(&p.norm).zip(&p.envelope) {
            let raw = v.get(*f) as i64;
            let c = raw.clamp(e.lo as i64, e.hi as i64);
            clamped |= c != raw;
            x.push(ref_norm(n.center, n.mult, n.shift, c));
        }
        let mid = ref_mlp(&self.part1, x.clone());
        x.push(ref_norm(
            p.mid_norm.center,
            p.mid_norm.mult,
            p.mid_norm.shift,
            mid,
        ));
        let out = ref_mlp(&self.part2, x);
        let angle = out.clamp(p.out_range.lo as i64, p.out_range.hi as i64);
        clamped |= angle != out;
        // As `CascadeNet::run` does: the filter's lift scale outside its training range.
        let k = v.get(Feature::FilterLiftScale);
        clamped |= k < p.lift_scale.lo || k > p.lift_scale.hi;
        // As `Estimator` does: a speed below the envelope's floor flags a model reading it, GPS
        // speed or the EGI velocity (`FeatureValues::low_speed`, `low_ground_speed`).
        let sources = p.features.iter().fold(0u32, |acc, f| acc | f.sources());
        clamped |= v.low_speed && sources & Channel::GpsSpeed.bit() != 0;
        clamped |= v.low_ground_speed && sources & estimator_core::features::VELOCITY_SOURCES != 0;
        RefOut {
            mid: mid as i32,
            angle: angle as i32,
            clamped,
        }
    }

    /// Parameter count (weights + biases).
    pub fn params(&self) -> usize {
        self.part1
            .iter()
            .chain(&self.part2)
            .map(|l| l.n_out() * (l.n_in() + 1))
            .sum()
    }

    /// Hidden widths, e.g. "512-256-128-64-32".
    pub fn widths(&self) -> String {
        self.part1
            .iter()
            .filter(|l| l.hidden)
            .map(|l| l.n_out().to_string())
            .collect::<Vec<_>>()
            .join("-")
    }
}

// ---------------------------------------------------------------------------------------------
// Code generation.

pub(crate) fn feature_path(f: Feature) -> String {
    match f {
        Feature::Sensor(c) => format!("crate::Feature::Sensor(crate::Channel::{c:?})"),
        Feature::Delta(c, l) => {
            format!("crate::Feature::Delta(crate::Channel::{c:?}, crate::Lag::{l:?})")
        }
        Feature::Sub(c, k) => format!("crate::Feature::Sub(crate::Channel::{c:?}, {k})"),
        other => format!("crate::Feature::{other:?}"),
    }
}

fn chain_type(layers: &[QLayer]) -> String {
    match layers {
        [] => String::new(),
        [last] => format!("crate::nn::Output<{}, {}>", last.n_in(), last.n_out()),
        [first, rest @ ..] => format!(
            "crate::nn::Chain<crate::nn::Hidden<{}, {}>, {}, {}>",
            first.n_in(),
            first.n_out(),
            chain_type(rest),
            first.n_out()
        ),
    }
}

fn dense_expr(l: &QLayer, out: &mut String) {
    out.push_str("crate::nn::Dense::new(\n[");
    for row in &l.weights {
        out.push('[');
        for w in row {
            let _ = write!(out, "{w},");
        }
        out.push_str("],\n");
    }
    out.push_str("],\n[");
    for b in &l.bias {
        let _ = write!(out, "{b},");
    }
    out.push_str("],\n[");
    for (m, s, o) in &l.requant {
        let _ = write!(
            out,
            "crate::nn::Requant {{ mult: {m}, shift: {s}, offset: {o} }},"
        );
    }
    out.push_str("],\n)");
}

fn chain_expr(layers: &[QLayer], out: &mut String) {
    match layers {
        [] => {}
        [last] => {
            out.push_str("crate::nn::Output(");
            dense_expr(last, out);
            out.push(')');
        }
        [first, rest @ ..] => {
            out.push_str("crate::nn::Chain(crate::nn::Hidden(");
            dense_expr(first, out);
            out.push_str("),\n");
            chain_expr(rest, out);
            out.push(')');
        }
    }
}

fn norm_expr(n: &Norm) -> String {
    format!(
        "crate::normalize::Norm {{ center: {}, mult: {}, shift: {} }}",
        n.center, n.mult, n.shift
    )
}

fn env_expr(e: &Envelope) -> String {
    format!(
        "crate::normalize::Envelope {{ lo: {}, hi: {} }}",
        e.lo, e.hi
    )
}

fn turbulence_expr(t: &TurbulenceEnvelope) -> String {
    format!(
        "crate::normalize::TurbulenceEnvelope {{ speed_lo_mms: {}, band_mms: {}, limit_urad: {:?} }}",
        t.speed_lo_mms, t.band_mms, t.limit_urad
    )
}

fn static_item(name: &str, q: &QCascade, out: &mut String) {
    let p = &q.prep;
    let n = p.features.len();
    let _ = writeln!(
        out,
        "/// {} cascade: {} features, hidden {} per part, {} parameters.",
        p.angle.symbol(),
        n,
        q.widths(),
        q.params()
    );
    let _ = writeln!(
        out,
        "pub static {name}: crate::CascadeNet<\n{},\n{},\n{n},\n{},\n> = crate::CascadeNet {{",
        chain_type(&q.part1),
        chain_type(&q.part2),
        n + 1
    );
    out.push_str("features: [");
    for f in &p.features {
        let _ = write!(out, "{}, ", feature_path(*f));
    }
    out.push_str("],\nnorm: [\n");
    for nm in &p.norm {
        let _ = writeln!(out, "{},", norm_expr(nm));
    }
    out.push_str("],\nenvelope: [\n");
    for e in &p.envelope {
        let _ = writeln!(out, "{},", env_expr(e));
    }
    out.push_str("],\npart1: ");
    chain_expr(&q.part1, out);
    let _ = write!(out, ",\nmid_norm: {},\npart2: ", norm_expr(&p.mid_norm));
    chain_expr(&q.part2, out);
    let _ = writeln!(
        out,
        ",\nout_range: {},\nturbulence: {},\nlift_scale: {},\n}};\n",
        env_expr(&p.out_range),
        turbulence_expr(&p.turbulence),
        env_expr(&p.lift_scale)
    );
}

/// The complete `weights.rs`: header, `ALPHA`, `BETA`, `PROVENANCE`, `AIRCRAFT_NAME` (the build's
/// aircraft, whose flights the trainer reads: estimator-core compiles the file only into a build
/// for the same aircraft).
pub fn generate(alpha: &QCascade, beta: &QCascade, provenance: &str) -> String {
    let mut out = String::new();
    out.push_str(
        "// @generated by `trainer train` (trainer/src/quant.rs). Do not edit: retrain and export instead.\n\
         // Included inside `mod generated` of estimator-core/src/model/mod.rs, hence the `crate::` paths.\n\
         // Every layer is built with the const fn `Dense::new`, so shapes, int8 range and accumulator\n\
         // head-room are checked at compile time.\n\n",
    );
    static_item(static_name(Angle::Alpha), alpha, &mut out);
    static_item(static_name(Angle::Beta), beta, &mut out);
    let _ = writeln!(
        out,
        "/// Where this model came from: dataset, seed, command, git revision and its test metrics.\n\
         pub const PROVENANCE: &str = {provenance:?};"
    );
    let _ = writeln!(
        out,
        "\n/// The aircraft whose flights trained this model (`aircraft/NAME.toml`).\n\
         pub const AIRCRAFT_NAME: &str = {:?};",
        estimator_core::aircraft::AIRCRAFT.name
    );
    out
}

// ---------------------------------------------------------------------------------------------
// Test vectors.

/// One vector: a sensor frame and the integer outputs the deployed model must produce for it, given
/// the frames since the last `reset` (the delta features' history).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Vector {
    /// Start of a sequence: the history is empty before this frame.
    pub reset: bool,
    pub frame: SensorFrame,
    pub alpha: RefOut,
    pub beta: RefOut,
}

/// The columns of a vector line for `suite`: its channels only (16 for Table 1, as every vector file
/// before the EGI suite, so a Table 1 model's vectors do not change; 23 for EGI).
pub fn vector_columns(suite: Suite) -> String {
    let sub = if carries_subsamples(suite) {
        format!(
            " sub_valid sub0..sub{} (sub-sample k of SUB_CHANNELS[i] at k·{} + i)",
            SUBSAMPLE_VALUES - 1,
            SUB_CHANNEL_COUNT
        )
    } else {
        String::new()
    };
    format!(
        "reset seq time_ms valid raw0..raw{}{sub} w_aero_mms alpha_mdeg alpha_clamped v_aero_mms beta_mdeg beta_clamped",
        channel_width(suite) - 1
    )
}

/// Number of sub-sample values a line of a suite that carries them holds after their validity.
const SUBSAMPLE_VALUES: usize = SUBSAMPLES * SUB_CHANNEL_COUNT;

fn carries_subsamples(suite: Suite) -> bool {
    suite.channels() & SUBSAMPLES_VALID != 0
}

/// Number of channels a vector line of `suite` carries.
fn channel_width(suite: Suite) -> usize {
    (suite.channels() & ALL_VALID).count_ones() as usize
}

/// Numbers a vector line of `suite` carries for its frame after `seq time_ms valid`: the
/// channels, then (`egi120`) the sub-samples' validity and values.
fn suite_width(suite: Suite) -> usize {
    channel_width(suite)
        + if carries_subsamples(suite) {
            1 + SUBSAMPLE_VALUES
        } else {
            0
        }
}

/// Vectors for `frames` (`(reset, frame)`: a reset starts a new sequence with an empty history),
/// computed by the integer reference on the features `estimator-core` derives.
pub fn vectors(alpha: &QCascade, beta: &QCascade, frames: &[(bool, SensorFrame)]) -> Vec<Vector> {
    let mut state = FeatureState::new(true);
    frames
        .iter()
        .map(|(reset, f)| {
            if *reset {
                state = FeatureState::new(true);
            }
            let v = state.next(f);
            Vector {
                reset: *reset,
                frame: *f,
                alpha: alpha.reference(&v),
                beta: beta.reference(&v),
            }
        })
        .collect()
}

/// Text format: `#` comment lines, then one line per vector of whitespace-separated integers
/// ([`vector_columns`]): 4 + 16 + 6 = 26 numbers for a Table 1 model, 4 + 23 + 6 = 33 for an EGI
/// one, 4 + 23 + 1 + 78 + 6 = 112 for an `egi120` one. Frames are written as a sender of `suite`
/// delivers them ([`SensorFrame::restricted_to`]).
pub fn format_vectors(vs: &[Vector], suite: Suite, header: &str) -> String {
    let mut out = String::new();
    for line in header.lines() {
        let _ = writeln!(out, "# {line}");
    }
    let _ = writeln!(out, "# columns: {}", vector_columns(suite));
    for v in vs {
        let f = v.frame.restricted_to(suite);
        let _ = write!(out, "{} {} {} {}", v.reset as u8, f.seq, f.time_ms, f.valid);
        for r in f.raw.iter().take(channel_width(suite)) {
            let _ = write!(out, " {r}");
        }
        if carries_subsamples(suite) {
            let _ = write!(out, " {}", f.sub.valid);
            for r in f.sub.raw.iter().flatten() {
                let _ = write!(out, " {r}");
            }
        }
        let _ = writeln!(
            out,
            " {} {} {} {} {} {}",
            v.alpha.mid,
            v.alpha.angle,
            v.alpha.clamped as u8,
            v.beta.mid,
            v.beta.angle,
            v.beta.clamped as u8
        );
    }
    out
}

/// Parses [`format_vectors`] output.
pub fn parse_vectors(text: &str) -> Option<Vec<Vector>> {
    let mut out = Vec::new();
    for line in text
        .lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.trim().is_empty())
    {
        let n: Vec<i64> = line
            .split_whitespace()
            .map(|t| t.parse().ok())
            .collect::<Option<_>>()?;
        let width = n.len().checked_sub(4 + 6)?;
        let suite = Suite::ALL.into_iter().find(|s| suite_width(*s) == width)?;
        let channels = channel_width(suite);
        let reset = n[0] == 1;
        let n = &n[1..];
        let mut frame = SensorFrame {
            seq: n[0] as u16,
            time_ms: n[1] as u32,
            valid: u32::try_from(n[2]).ok()?,
            ..SensorFrame::default()
        };
        for (r, v) in frame.raw.iter_mut().zip(&n[3..3 + channels]) {
            *r = *v as i32;
        }
        if carries_subsamples(suite) {
            frame.sub.valid = u16::try_from(n[3 + channels]).ok()?;
            let values = &n[4 + channels..3 + width];
            for (r, v) in frame.sub.raw.iter_mut().flatten().zip(values) {
                *r = *v as i32;
            }
        }
        let ro = |k: usize| RefOut {
            mid: n[k] as i32,
            angle: n[k + 1] as i32,
            clamped: n[k + 2] != 0,
        };
        out.push(Vector {
            reset,
            frame,
            alpha: ro(3 + width),
            beta: ro(6 + width),
        });
    }
    Some(out)
}

/// Name of an angle's static in the generated file.
pub fn static_name(a: Angle) -> &'static str {
    match a {
        Angle::Alpha => "ALPHA",
        Angle::Beta => "BETA",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E[((w − q·s)·x)²] over `inputs`: the output error a rounding leaves on them.
    fn output_error(row: &[f32], q: &[i8], s: f64, inputs: &[Vec<f32>]) -> f64 {
        inputs
            .iter()
            .map(|x| {
                let e: f64 = row
                    .iter()
                    .zip(q)
                    .zip(x)
                    .map(|((w, q), x)| (f64::from(*w) - f64::from(*q) * s) * f64::from(*x))
                    .sum();
                e * e
            })
            .sum::<f64>()
            / inputs.len() as f64
    }

    fn layer(rows: Vec<Vec<f32>>) -> FloatLayer {
        let bias = vec![0.0; rows.len()];
        FloatLayer {
            weights: rows,
            bias,
        }
    }

    #[test]
    fn uncorrelated_inputs_or_none_round_to_nearest() {
        // One large weight sets the scale (127 steps of 0.01); the others fall between steps.
        let l = layer(vec![vec![1.27, 0.004, -0.016, 0.0251]]);
        let nearest = vec![127, 0, -2, 3];
        let basis: Vec<Vec<f32>> = (0..4)
            .map(|i| (0..4).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
            .collect();
        for inputs in [&basis[..], &[]] {
            let [(q, s)] = &round_rows(&l, inputs)[..] else {
                panic!("one row in, one row out")
            };
            assert_eq!(q, &nearest);
            assert!((s - 0.01).abs() < 1e-9);
        }
    }

    #[test]
    fn correlated_inputs_move_the_rounding_error_onto_the_next_weight() {
        // Two inputs that move together: the error of rounding the first is carried by the second,
        // so the output error on those inputs falls far below rounding each weight alone.
        let l = layer(vec![vec![1.27, 0.0149, 0.0149, -0.3]]);
        let inputs: Vec<Vec<f32>> = (0..200)
            .map(|k| {
                let t = (k as f32 * 0.37).sin();
                let u = (k as f32 * 1.91).cos();
                vec![u, t, t + 0.01 * u, 0.5 * u]
            })
            .collect();
        let [(q, s)] = &round_rows(&l, &inputs)[..] else {
            panic!("one row in, one row out")
        };
        let nearest: Vec<i8> = l.weights[0]
            .iter()
            .map(|w| (f64::from(*w) / s).round() as i8)
            .collect();
        assert_eq!(nearest, vec![127, 1, 1, -30]);
        let gptq = output_error(&l.weights[0], q, *s, &inputs);
        let plain = output_error(&l.weights[0], &nearest, *s, &inputs);
        assert!(
            gptq < 0.25 * plain,
            "GPTQ {gptq:e} against nearest {plain:e}"
        );
        // Every weight stays on the int8 grid of the row's own scale.
        assert!(q.iter().all(|v| (-127..=127).contains(v)));
        assert!((s - 0.01).abs() < 1e-9);
    }
}
