//! Fitting the estimate's 1σ (`estimator_core::uncertainty`): the weights of its terms, per angle.
//!
//! The compiled-in estimator is stepped over flights no network of it trained on, exactly as the
//! firmware steps it; every computed (usable) frame gives a row: the terms of each angle and the
//! angle's error against the truth. The weights maximise the Gaussian likelihood of the errors
//! (coordinate search in steps of the weights, each weight ≥ 0), then all of an angle's weights are
//! multiplied by one factor so that 95 % of the rows lie within 2σ: the errors have heavier tails
//! than a Gaussian, and the likelihood alone sets σ for their bulk. The result is quantized to the
//! Q8 weights the estimator computes with, and its coverage is measured with the estimator's own
//! integer σ.

use crate::error::{Error, Result};
use estimator_core::uncertainty::{self, Coefficients, TERMS, Term};
use serde::Serialize;

/// The rows of one angle: its terms, the 1σ the estimator reported (millidegrees) and its error
/// (millidegrees) on each frame where it was computed, and where that frame is: the flight's
/// position in the list of flight names given to [`write_rows`] and the frame's 0-based index in
/// its flight (its data row in the flight's CSV).
#[derive(Default, Clone)]
pub struct Rows {
    pub terms: Vec<[u32; TERMS]>,
    pub sigma_mdeg: Vec<u16>,
    pub err_mdeg: Vec<f64>,
    pub at: Vec<(u32, u32)>,
}

impl Rows {
    pub fn push(&mut self, terms: [u32; TERMS], sigma_mdeg: u16, err_mdeg: f64, at: (u32, u32)) {
        self.terms.push(terms);
        self.sigma_mdeg.push(sigma_mdeg);
        self.err_mdeg.push(err_mdeg);
        self.at.push(at);
    }

    pub fn extend(&mut self, other: Rows) {
        self.terms.extend(other.terms);
        self.sigma_mdeg.extend(other.sigma_mdeg);
        self.err_mdeg.extend(other.err_mdeg);
        self.at.extend(other.at);
    }

    pub fn len(&self) -> usize {
        self.err_mdeg.len()
    }

    pub fn is_empty(&self) -> bool {
        self.err_mdeg.is_empty()
    }

    /// Every `n`-th row.
    pub fn every(&self, n: usize) -> Rows {
        let n = n.max(1);
        Rows {
            terms: self.terms.iter().step_by(n).copied().collect(),
            sigma_mdeg: self.sigma_mdeg.iter().step_by(n).copied().collect(),
            err_mdeg: self.err_mdeg.iter().step_by(n).copied().collect(),
            at: self.at.iter().step_by(n).copied().collect(),
        }
    }
}

/// How often |error| ≤ 1σ and ≤ 2σ (a Gaussian: 68.3 % and 95.4 %), over the frames with a 1σ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Coverage {
    pub frames: usize,
    pub within_1sigma: f64,
    pub within_2sigma: f64,
    /// Median 1σ, degrees.
    pub median_sigma_deg: f64,
}

impl Coverage {
    /// Of (1σ, error) pairs in millidegrees.
    pub fn of(pairs: impl Iterator<Item = (u16, f64)>) -> Coverage {
        let (mut n, mut one, mut two) = (0usize, 0usize, 0usize);
        let mut sig = Vec::new();
        for (s, e) in pairs {
            let s = f64::from(s);
            n += 1;
            one += usize::from(e.abs() <= s);
            two += usize::from(e.abs() <= 2.0 * s);
            sig.push(s);
        }
        if n == 0 {
            return Coverage::default();
        }
        sig.sort_by(f64::total_cmp);
        Coverage {
            frames: n,
            within_1sigma: one as f64 / n as f64,
            within_2sigma: two as f64 / n as f64,
            median_sigma_deg: sig[n / 2] / 1000.0,
        }
    }
}

/// The 1σ (millidegrees) of continuous weights `w` at one row's terms.
fn sigma_f(w: &[f64; TERMS], t: &[u32; TERMS]) -> f64 {
    w.iter()
        .zip(t)
        .map(|(w, t)| (w * f64::from(*t)).powi(2))
        .sum::<f64>()
        .sqrt()
        .max(1.0)
}

/// Mean negative log-likelihood (without its constant) of the errors under N(0, σ²).
fn nll(w: &[f64; TERMS], rows: &Rows) -> f64 {
    let n = rows.len().max(1) as f64;
    rows.terms
        .iter()
        .zip(&rows.err_mdeg)
        .map(|(t, e)| {
            let s = sigma_f(w, t);
            s.ln() + 0.5 * (e / s).powi(2)
        })
        .sum::<f64>()
        / n
}

/// The coverage of `rows` under Q8 weights `weights`, with the estimator's integer 1σ.
pub fn coverage_with(weights: &[u16; TERMS], rows: &Rows) -> Coverage {
    Coverage::of(
        rows.terms
            .iter()
            .map(|t| uncertainty::sigma(weights, t))
            .zip(rows.err_mdeg.iter().copied()),
    )
}

/// What the fit of one angle found.
#[derive(Clone, Debug, Serialize)]
pub struct AngleFit {
    /// Q8 weights, per term (in `Term::ALL` order).
    pub weights: [u16; TERMS],
    /// The common factor that brought 2σ to the 95th percentile.
    pub factor: f64,
    /// On the fitting rows, with the estimator's integer 1σ of these weights.
    pub coverage: Coverage,
}

/// The weights of one angle.
pub fn fit(rows: &Rows) -> Result<AngleFit> {
    if rows.len() < 1000 {
        return Err(Error::Numeric(format!(
            "fit-sigma: {} usable frames is too few to fit the 1σ (give more flights)",
            rows.len()
        )));
    }
    let mut abs: Vec<f64> = rows.err_mdeg.iter().map(|e| e.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let median = abs[abs.len() / 2].max(1.0);
    let mut w = [0.3f64; TERMS];
    w[Term::Base as usize] = 1.25 * median / 1000.0;
    // A term that is 0 on every row (e.g. a scale the filter holds at 1) leaves the likelihood
    // alone whatever its weight: it gets 0, not the start value.
    for (k, wk) in w.iter_mut().enumerate() {
        if rows.terms.iter().all(|t| t.get(k) == Some(&0)) {
            *wk = 0.0;
        }
    }
    let mut best = nll(&w, rows);
    for _ in 0..40 {
        let before = best;
        for k in 0..TERMS {
            let cur = w[k];
            let candidates: &[f64] = if cur == 0.0 {
                &[0.02, 0.1, 0.5]
            } else {
                &[0.0, 0.5, 0.7, 0.85, 0.93, 1.07, 1.2, 1.4, 2.0]
            };
            for &c in candidates {
                let mut trial = w;
                trial[k] = if cur == 0.0 { c } else { cur * c };
                let v = nll(&trial, rows);
                if v < best {
                    best = v;
                    w = trial;
                }
            }
        }
        if before - best < 1e-6 {
            break;
        }
    }
    // One factor for 2σ at the 95th percentile of |e| / σ.
    let mut ratio: Vec<f64> = rows
        .terms
        .iter()
        .zip(&rows.err_mdeg)
        .map(|(t, e)| e.abs() / (2.0 * sigma_f(&w, t)))
        .collect();
    ratio.sort_by(f64::total_cmp);
    let factor = ratio[(0.95 * (ratio.len() - 1) as f64).round() as usize].max(1e-3);
    let weights = w.map(|x| (x * factor * 256.0).round().clamp(0.0, f64::from(u16::MAX)) as u16);
    let coverage = coverage_with(&weights, rows);
    Ok(AngleFit {
        weights,
        factor,
        coverage,
    })
}

/// The generated `sigma.rs` of both angles' fits, for the networks whose `PROVENANCE` is
/// `model`.
pub fn rust_file(alpha: &AngleFit, beta: &AngleFit, provenance: &str, model: &str) -> String {
    let arr = |w: &[u16; TERMS]| w.iter().map(u16::to_string).collect::<Vec<_>>().join(", ");
    let names = Term::ALL.map(Term::name).join(", ");
    let c = Coefficients {
        alpha: alpha.weights,
        beta: beta.weights,
    };
    format!(
        "// @generated by `trainer fit-sigma` (trainer/src/uncertainty.rs). Do not edit: re-fit instead.\n\
         // Included inside `mod sigma` of estimator-core/src/model/mod.rs, hence the `crate::` paths.\n\n\
         /// The 1σ weights (Q8) of the estimate, per term ({names}).\n\
         pub const SIGMA: crate::uncertainty::Coefficients = crate::uncertainty::Coefficients {{\n    \
         alpha: [{}],\n    beta: [{}],\n}};\n\n\
         /// How [`SIGMA`] was fitted.\n\
         pub const SIGMA_PROVENANCE: &str = {:?};\n\n\
         /// The `PROVENANCE` of the networks [`SIGMA`] was fitted for.\n\
         pub const SIGMA_MODEL_PROVENANCE: &str = {:?};\n",
        arr(&c.alpha),
        arr(&c.beta),
        provenance,
        model
    )
}

/// Every row as CSV: dataset, flight (`flights[dataset][flight position]`: the manifest's flight
/// name; `hil-sim` writes its CSV as `NAME.csv`), the frame's 0-based index in its flight (CSV
/// line = frame + 2), angle, the terms (named), the 1σ and the error, millidegrees (the error to
/// 0.001).
pub fn write_rows(
    path: &std::path::Path,
    names: &[String],
    flights: &[Vec<String>],
    per_dataset: &[[Rows; 2]],
) -> std::io::Result<()> {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let head: Vec<&str> = Term::ALL.iter().map(|t| t.name()).collect();
    writeln!(
        w,
        "dataset,flight,frame,angle,{},sigma_mdeg,err_mdeg",
        head.join(",")
    )?;
    for ((name, fl), rows) in names.iter().zip(flights).zip(per_dataset) {
        for (angle, r) in ["alpha", "beta"].iter().zip(rows) {
            for (((t, s), e), (f, i)) in r
                .terms
                .iter()
                .zip(&r.sigma_mdeg)
                .zip(&r.err_mdeg)
                .zip(&r.at)
            {
                let t: Vec<String> = t.iter().map(u32::to_string).collect();
                let flight = fl.get(*f as usize).map_or("?", String::as_str);
                writeln!(w, "{name},{flight},{i},{angle},{},{s},{e:.3}", t.join(","))?;
            }
        }
    }
    w.flush()
}
