//! Table 2 baselines on the same features, split and test flights: closed-form linear regression,
//! gradient boosting (gbdt), and a plain MLP (burn).
use crate::data::{Dataset, Flight, Role, feature_si, spread_rows};
use crate::error::{Error, Result};
use crate::metrics::FlightMetrics;
use crate::model::{Mlp, TrainConfig, predict_all, train};
use crate::prep::{Angle, Prep};
use estimator_core::Feature;

/// Standardised float features (raw × LSB, then training mean/std) of every row.
struct Design {
    mean: Vec<f64>,
    std: Vec<f64>,
}

impl Design {
    fn fit(features: &[Feature], train: &[&Flight]) -> Design {
        let n: usize = train.iter().map(|f| f.len()).sum();
        let mut mean = vec![0.0; features.len()];
        let mut sq = vec![0.0; features.len()];
        for fl in train {
            for v in &fl.features {
                for (k, f) in features.iter().enumerate() {
                    let x = feature_si(v, *f);
                    mean[k] += x;
                    sq[k] += x * x;
                }
            }
        }
        let nf = n.max(1) as f64;
        let std = mean
            .iter_mut()
            .zip(&sq)
            .map(|(m, s)| {
                *m /= nf;
                let sd = (s / nf - *m * *m).max(0.0).sqrt();
                if sd > 0.0 { sd } else { 1.0 }
            })
            .collect();
        Design { mean, std }
    }

    fn row(&self, features: &[Feature], v: &estimator_core::FeatureValues) -> Vec<f64> {
        features
            .iter()
            .enumerate()
            .map(|(k, f)| (feature_si(v, *f) - self.mean[k]) / self.std[k])
            .collect()
    }
}

/// Solves the symmetric positive definite system `a x = b` (Cholesky). `a` is `n × n` row-major.
pub fn cholesky_solve(mut a: Vec<f64>, mut b: Vec<f64>, n: usize) -> Result<Vec<f64>> {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d <= 0.0 || !d.is_finite() {
            return Err(Error::Numeric(format!(
                "normal equations not positive definite at column {j} (constant or collinear feature?)"
            )));
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i * n + k] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= a[k * n + i] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    Ok(b)
}

/// Least squares with an intercept on standardised features; a tiny ridge term (1e-9 × rows) keeps
/// the normal equations definite when a feature is constant (e.g. an unused speedbrake).
pub fn linear_fit(x: &[Vec<f64>], y: &[f64]) -> Result<Vec<f64>> {
    let p = x.first().map_or(0, |r| r.len()) + 1;
    let mut a = vec![0.0; p * p];
    let mut b = vec![0.0; p];
    for (r, t) in x.iter().zip(y) {
        let mut z = Vec::with_capacity(p);
        z.push(1.0);
        z.extend_from_slice(r);
        for i in 0..p {
            b[i] += z[i] * t;
            for j in 0..p {
                a[i * p + j] += z[i] * z[j];
            }
        }
    }
    for i in 1..p {
        a[i * p + i] += 1e-9 * x.len() as f64 + 1e-12;
    }
    cholesky_solve(a, b, p)
}

fn linear_predict(coef: &[f64], x: &[f64]) -> f64 {
    coef[0] + coef[1..].iter().zip(x).map(|(c, v)| c * v).sum::<f64>()
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Baseline {
    Linear,
    GradientBoosting,
    Mlp,
}

impl Baseline {
    pub const fn name(self) -> &'static str {
        match self {
            Baseline::Linear => "Linear regression",
            Baseline::GradientBoosting => "Gradient boosting",
            Baseline::Mlp => "Plain MLP",
        }
    }
}

/// A model's answers on the test flights (degrees, per flight in test order) and their metrics,
/// and its answers on any extra flights it was asked about (e.g. out-of-distribution ones).
#[derive(Debug, Clone, Default)]
pub struct Scored {
    pub metrics: FlightMetrics,
    pub preds: Vec<(String, Vec<f64>)>,
    pub extra_preds: Vec<(String, Vec<f64>)>,
}

fn test_metrics(
    ds: &Dataset,
    angle: Angle,
    extra: &[&Flight],
    mut pred: impl FnMut(&Flight) -> Vec<f64>,
) -> Scored {
    let fl: Vec<(String, Vec<f64>, Vec<f64>)> = ds
        .flights(Role::Test)
        .map(|f| (f.name.clone(), pred(f), f.truth(angle.target()).to_vec()))
        .collect();
    Scored {
        metrics: FlightMetrics::of_banded(&fl, angle.bands()),
        preds: fl.into_iter().map(|(n, p, _)| (n, p)).collect(),
        extra_preds: extra.iter().map(|f| (f.name.clone(), pred(f))).collect(),
    }
}

/// Fits a baseline on the training flights and scores it on the test flights (degrees); also
/// answers on `extra` flights (none: pass `&[]`).
#[allow(clippy::too_many_arguments)]
pub fn run_baseline(
    kind: Baseline,
    ds: &Dataset,
    angle: Angle,
    features: &[Feature],
    hidden: &[usize],
    cfg: &TrainConfig,
    gb_rows: usize,
    extra: &[&Flight],
) -> Result<Scored> {
    let tr: Vec<&Flight> = ds.flights(Role::Train).collect();
    match kind {
        Baseline::Linear => {
            let d = Design::fit(features, &tr);
            let mut x = Vec::new();
            let mut y = Vec::new();
            for fl in &tr {
                for (v, t) in fl.features.iter().zip(fl.truth(angle.target())) {
                    x.push(d.row(features, v));
                    y.push(*t);
                }
            }
            let coef = linear_fit(&x, &y)?;
            Ok(test_metrics(ds, angle, extra, |f| {
                f.features
                    .iter()
                    .map(|v| linear_predict(&coef, &d.row(features, v)))
                    .collect()
            }))
        }
        Baseline::GradientBoosting => {
            use gbdt::config::Config;
            use gbdt::decision_tree::Data;
            use gbdt::gradient_boost::GBDT;
            let d = Design::fit(features, &tr);
            let mut data: Vec<Data> = spread_rows(&tr, gb_rows)
                .into_iter()
                .map(|(fl, i)| {
                    let x: Vec<f32> = d
                        .row(features, &fl.features[i])
                        .iter()
                        .map(|x| *x as f32)
                        .collect();
                    Data::new_training_data(x, 1.0, fl.truth(angle.target())[i] as f32, None)
                })
                .collect();
            let mut conf = Config::new();
            conf.set_feature_size(features.len());
            conf.set_max_depth(6);
            conf.set_iterations(200);
            conf.set_shrinkage(0.1);
            conf.set_loss("SquaredError");
            conf.set_min_leaf_size(20);
            conf.set_data_sample_ratio(1.0);
            conf.set_feature_sample_ratio(1.0);
            conf.set_training_optimization_level(2);
            let mut gb = GBDT::new(&conf);
            gb.fit(&mut data);
            Ok(test_metrics(ds, angle, extra, |f| {
                let test: Vec<Data> = f
                    .features
                    .iter()
                    .map(|v| {
                        let x: Vec<f32> = d.row(features, v).iter().map(|x| *x as f32).collect();
                        Data::new_test_data(x, None)
                    })
                    .collect();
                gb.predict(&test).iter().map(|p| *p as f64).collect()
            }))
        }
        Baseline::Mlp => {
            let va: Vec<&Flight> = ds.flights(Role::Val).collect();
            let prep = Prep::fit(angle, features, &tr);
            let n_in = prep.n_inputs();
            let mut dims = vec![n_in];
            dims.extend_from_slice(hidden);
            dims.push(1);
            let (model, _) = train(
                |dev| Mlp::new(&dims, dev),
                cfg,
                &prep.matrix(&tr),
                &prep.matrix(&va),
            );
            Ok(test_metrics(ds, angle, extra, |f| {
                let (_, po) = predict_all(&model, &prep.inputs(&[f]), n_in);
                po.iter().map(|z| prep.out_deg(*z as f64)).collect()
            }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_fit_recovers_exact_coefficients() {
        let x: Vec<Vec<f64>> = (0..50)
            .map(|i| vec![(i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()])
            .collect();
        let y: Vec<f64> = x.iter().map(|r| 1.5 - 2.0 * r[0] + 0.25 * r[1]).collect();
        let c = linear_fit(&x, &y).unwrap();
        assert!(
            (c[0] - 1.5).abs() < 1e-6 && (c[1] + 2.0).abs() < 1e-6 && (c[2] - 0.25).abs() < 1e-6,
            "{c:?}"
        );
    }

    #[test]
    fn cholesky_rejects_singular_systems() {
        assert!(cholesky_solve(vec![1.0, 1.0, 1.0, 1.0], vec![1.0, 1.0], 2).is_err());
    }
}
