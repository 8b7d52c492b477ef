//! Normalisation shared by training, quantization and the integer reference: the float model is
//! trained on exactly the scaling the integer `Norm`s apply (integer centers, `mult / 2^shift` slopes).
use crate::data::{Flight, Target};
use crate::model::Matrix;
use estimator_core::normalize::{Envelope, Norm, ONE_SIGMA, TURBULENCE_BANDS, TurbulenceEnvelope};
use estimator_core::{Feature, FeatureValues};

/// Largest `|z|` the int16 input can carry (32767 / 4096).
pub const Z_MAX: f64 = i16::MAX as f64 / ONE_SIGMA as f64;

/// `(mult, shift)` with `mult / 2^shift ≈ ratio`, `1 ≤ shift ≤ 62`, `0 < mult ≤ limit`.
pub fn fixed_point(ratio: f64, limit: i64) -> (i32, u8) {
    let mut best = (1i32, 62u8);
    for shift in (1..=62u8).rev() {
        let m = (ratio * (1u64 << shift) as f64).round();
        if m >= 1.0 && m <= limit as f64 {
            best = (m as i32, shift);
            break;
        }
    }
    best
}

/// Real value of `mult / 2^shift`.
pub fn fp_value(mult: i32, shift: u8) -> f64 {
    mult as f64 / (1u64 << shift) as f64
}

/// A `Norm` mapping `center ± sigma` (raw units) to `±ONE_SIGMA`; `mult ≤ 2^30` so `(raw - center) ×
/// mult` cannot overflow i64 even for the full i32 range.
pub fn norm_for(center: i32, sigma: f64) -> Norm {
    let sigma = if sigma.is_finite() && sigma > 0.0 {
        sigma
    } else {
        1.0
    };
    let (mult, shift) = fixed_point(ONE_SIGMA as f64 / sigma, 1 << 30);
    Norm {
        center,
        mult,
        shift,
    }
}

/// Float image of `Norm::apply` divided by ONE_SIGMA (no rounding, same slope and center).
pub fn norm_z(n: Norm, raw: f64) -> f64 {
    (raw - n.center as f64) * fp_value(n.mult, n.shift) / ONE_SIGMA as f64
}

fn mean_std(v: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let (mut n, mut s, mut s2) = (0f64, 0f64, 0f64);
    for x in v {
        n += 1.0;
        s += x;
        s2 += x * x;
    }
    let m = s / n.max(1.0);
    (m, (s2 / n.max(1.0) - m * m).max(0.0).sqrt())
}

/// Which angle a cascade estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Angle {
    Alpha,
    Beta,
}

impl Angle {
    /// The regime bands of this angle's error tables.
    pub fn bands(self) -> crate::metrics::BandSet {
        match self {
            Angle::Alpha => crate::metrics::BandSet::Alpha,
            Angle::Beta => crate::metrics::BandSet::Beta,
        }
    }

    pub fn target(self) -> Target {
        match self {
            Angle::Alpha => Target::AlphaDeg,
            Angle::Beta => Target::BetaDeg,
        }
    }
    pub fn intermediate(self) -> Target {
        match self {
            Angle::Alpha => Target::WAero,
            Angle::Beta => Target::VAero,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Angle::Alpha => "alpha",
            Angle::Beta => "beta",
        }
    }
    pub fn symbol(self) -> &'static str {
        match self {
            Angle::Alpha => "α",
            Angle::Beta => "β",
        }
    }
}

/// Scaling of one angle's cascade, fitted on training flights only.
#[derive(Debug, Clone)]
pub struct Prep {
    pub angle: Angle,
    pub features: Vec<Feature>,
    pub norm: Vec<Norm>,
    pub envelope: Vec<Envelope>,
    /// Intermediate (mm/s) → part-2 input.
    pub mid_norm: Norm,
    /// Angle (millidegrees) center and standard deviation.
    pub out_center: i32,
    pub out_sigma: f64,
    pub out_range: Envelope,
    /// Turbulence trained on, by filter airspeed: `ANY` from [`Prep::fit`]; `train_angle` sets
    /// [`turbulence_envelope`] for a model that reads the filter.
    pub turbulence: TurbulenceEnvelope,
    /// The filter's lift scale over the training frames: `ANY` from [`Prep::fit`]; `train_angle`
    /// sets [`lift_scale_envelope`] for a model that reads the filter.
    pub lift_scale: Envelope,
}

/// Share of a band's training frames at or below its turbulence limit: the rest (one frame in a
/// thousand) is what the envelope calls turbulence training did not fly.
pub const TURBULENCE_QUANTILE: f64 = 0.999;

/// Filter-airspeed bands of the turbulence envelope: from 60 m/s in 20 m/s steps (the first band
/// takes everything below 80 m/s, the last everything above 200 m/s).
const TURBULENCE_SPEED_LO_MPS: f64 = 60.0;
const TURBULENCE_BAND_MPS: f64 = 20.0;

/// A band with fewer training frames than this (25 s) has no trained turbulence: limit 0, so any
/// turbulence there is flagged.
const TURBULENCE_MIN_FRAMES: usize = 500;

/// Per filter-airspeed band, the [`TURBULENCE_QUANTILE`] of the filter's turbulence index over the
/// training frames on which the filter had its inputs and did not restart (the frames
/// `Estimator::step` judges).
pub fn turbulence_envelope(train: &[&Flight]) -> TurbulenceEnvelope {
    let mms = |mps: f64| (mps * 1e3).round() as i32;
    let mut env = TurbulenceEnvelope {
        speed_lo_mms: mms(TURBULENCE_SPEED_LO_MPS),
        band_mms: mms(TURBULENCE_BAND_MPS),
        limit_urad: [0; TURBULENCE_BANDS],
    };
    let mut bands: Vec<Vec<i32>> = vec![Vec::new(); TURBULENCE_BANDS];
    for v in train
        .iter()
        .flat_map(|f| f.features.iter())
        .filter(|v| v.filter_fresh())
    {
        if let Some(b) = bands.get_mut(env.band(v.get(Feature::FilterAirspeed))) {
            b.push(v.get(Feature::FilterTurbulence));
        }
    }
    for (limit, mut b) in env.limit_urad.iter_mut().zip(bands) {
        if b.len() >= TURBULENCE_MIN_FRAMES {
            let k = ((TURBULENCE_QUANTILE * b.len() as f64).ceil() as usize).clamp(1, b.len()) - 1;
            *limit = *b.select_nth_unstable(k).1;
        }
    }
    env
}

/// Smallest and largest lift scale of the air-data filter over the training frames (as for an
/// input's envelope): outside it a model that reads the filter is flown where the aerodynamic model
/// and the sensors disagree as training never saw, and `CascadeNet::run` says so.
pub fn lift_scale_envelope(train: &[&Flight]) -> Envelope {
    training_range(train, Feature::FilterLiftScale).unwrap_or(Envelope::ANY)
}

/// Smallest and largest value of `f` over the training frames (`None` without frames): what an
/// input's envelope is.
fn training_range(train: &[&Flight], f: Feature) -> Option<Envelope> {
    let values = || {
        train
            .iter()
            .flat_map(|fl| fl.features.iter())
            .map(|v| v.get(f))
    };
    Some(Envelope {
        lo: values().min()?,
        hi: values().max()?,
    })
}

/// Rows of `flights` that have their features.
fn feature_rows(flights: &[&Flight]) -> usize {
    flights.iter().map(|fl| fl.features.len()).sum()
}

impl Prep {
    pub fn fit(angle: Angle, features: &[Feature], train: &[&Flight]) -> Prep {
        let rows = || train.iter().flat_map(|f| f.features.iter());
        let mut norm = Vec::new();
        let mut envelope = Vec::new();
        for f in features {
            let vals = rows().map(|v| v.get(*f) as f64);
            let (m, s) = mean_std(vals);
            norm.push(norm_for(m.round() as i32, s));
            envelope.push(training_range(train, *f).unwrap_or(Envelope { lo: 0, hi: 0 }));
        }
        let mid = || {
            train
                .iter()
                .flat_map(|f| f.truth(angle.intermediate()).iter().map(|v| v * 1000.0))
        };
        let (mm, ms) = mean_std(mid());
        let out = || {
            train
                .iter()
                .flat_map(|f| f.truth(angle.target()).iter().map(|v| v * 1000.0))
        };
        let (om, os) = mean_std(out());
        let lo = out().fold(f64::INFINITY, f64::min).floor() as i32;
        let hi = out().fold(f64::NEG_INFINITY, f64::max).ceil() as i32;
        Prep {
            angle,
            features: features.to_vec(),
            norm,
            envelope,
            mid_norm: norm_for(mm.round() as i32, ms),
            out_center: om.round() as i32,
            out_sigma: if os > 0.0 { os } else { 1.0 },
            out_range: Envelope { lo, hi },
            turbulence: TurbulenceEnvelope::ANY,
            lift_scale: Envelope::ANY,
        }
    }

    pub fn n_inputs(&self) -> usize {
        self.features.len()
    }

    /// Network input (in σ) of one frame: clamped to the envelope and the int16 range like the target.
    pub fn input(&self, v: &FeatureValues, out: &mut Vec<f32>) {
        for ((f, n), e) in self.features.iter().zip(&self.norm).zip(&self.envelope) {
            let (raw, _) = e.clamp(v.get(*f));
            out.push(norm_z(*n, raw as f64).clamp(-Z_MAX, Z_MAX) as f32);
        }
    }

    /// Normalised intermediate target from m/s.
    pub fn mid_z(&self, mps: f64) -> f32 {
        norm_z(self.mid_norm, mps * 1000.0) as f32
    }
    /// Normalised angle target from degrees.
    pub fn out_z(&self, deg: f64) -> f32 {
        ((deg * 1000.0 - self.out_center as f64) / self.out_sigma) as f32
    }
    /// Degrees from a normalised angle, clamped to the training range like the estimator.
    pub fn out_deg(&self, z: f64) -> f64 {
        let mdeg = z * self.out_sigma + self.out_center as f64;
        mdeg.clamp(self.out_range.lo as f64, self.out_range.hi as f64) / 1000.0
    }

    /// Inputs and both normalised targets of every row of `flights`.
    pub fn matrix(&self, flights: &[&Flight]) -> Matrix {
        let rows = feature_rows(flights);
        let mut ym = Vec::with_capacity(rows);
        let mut yo = Vec::with_capacity(rows);
        for fl in flights {
            let mid = fl.truth(self.angle.intermediate());
            let out = fl.truth(self.angle.target());
            ym.extend(mid.iter().take(fl.features.len()).map(|v| self.mid_z(*v)));
            yo.extend(out.iter().take(fl.features.len()).map(|v| self.out_z(*v)));
        }
        Matrix {
            x: self.inputs(flights),
            ym,
            yo,
            n_in: self.n_inputs(),
        }
    }

    /// Network inputs of every row of `flights` (row-major, `n_inputs()` per row).
    pub fn inputs(&self, flights: &[&Flight]) -> Vec<f32> {
        // Sized once: a vector grown by doubling holds up to twice its rows while it moves (some
        // 6 GB more for the 13 M rows of the shipped recipe on 24 randomised airframes).
        let mut x = Vec::with_capacity(feature_rows(flights).saturating_mul(self.n_inputs()));
        for fl in flights {
            for v in &fl.features {
                self.input(v, &mut x);
            }
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_is_close_and_in_range() {
        for r in [1e-9, 3.3e-5, 0.0137, 1.0, 4096.0 / 3.0, 4096.0] {
            let (m, s) = fixed_point(r, 1 << 30);
            assert!((1..=62).contains(&s));
            assert!((1..=1 << 30).contains(&m));
            assert!((fp_value(m, s) - r).abs() / r < 1e-6, "{r}");
        }
    }

    #[test]
    fn norm_for_maps_one_sigma_to_4096() {
        let n = norm_for(1000, 250.0);
        assert_eq!(n.apply(1000), 0);
        assert_eq!(n.apply(1250), 4096);
        assert_eq!(n.apply(750), -4096);
        assert!((norm_z(n, 1250.0) - 1.0).abs() < 1e-9);
    }
}
