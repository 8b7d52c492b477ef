//! Feature analysis: Spearman rank correlations (candidate features vs air-data targets and among
//! themselves) and sampled Shapley values (permutation sampling against a training background).
use crate::data::{Dataset, Role, Target, feature_si, spread_rows};
use estimator_core::{Feature, FeatureValues};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

/// Ranks 1..=n, ties get the mean of their ranks.
pub fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let rank = (i + j) as f64 / 2.0 + 1.0;
        for &k in &idx[i..=j] {
            r[k] = rank;
        }
        i = j + 1;
    }
    r
}

/// Pearson correlation; NaN when either side is constant.
pub fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()) as f64;
    if n < 2.0 {
        return f64::NAN;
    }
    let ma = a.iter().sum::<f64>() / n;
    let mb = b.iter().sum::<f64>() / n;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    if saa == 0.0 || sbb == 0.0 {
        return f64::NAN;
    }
    sab / (saa * sbb).sqrt()
}

/// Spearman rank correlation (Pearson on tie-averaged ranks).
pub fn spearman(a: &[f64], b: &[f64]) -> f64 {
    pearson(&ranks(a), &ranks(b))
}

/// Named columns of evenly subsampled training rows: every candidate feature (SI value the models
/// see) followed by the four targets. Only training and validation flights are read.
pub fn columns(ds: &Dataset, max_rows: usize) -> (Vec<String>, Vec<Vec<f64>>) {
    let fl: Vec<_> = ds.flights.iter().filter(|f| f.role != Role::Test).collect();
    let mut names: Vec<String> = Feature::ALL.iter().map(|f| f.name().to_string()).collect();
    names.extend(Target::ALL.iter().map(|t| t.column().to_string()));
    let mut cols = vec![Vec::new(); names.len()];
    for (f, i) in spread_rows(&fl, max_rows) {
        for (c, feat) in Feature::ALL.iter().enumerate() {
            cols[c].push(feature_si(&f.features[i], *feat));
        }
        for (t, tgt) in Target::ALL.iter().enumerate() {
            cols[Feature::ALL.len() + t].push(f.truth(*tgt)[i]);
        }
    }
    (names, cols)
}

/// The `n` feature columns most correlated (max |ρ|) with the α or β target, in their original
/// order, followed by every target column: names and the sub-matrix. `names`/`m` are
/// [`columns`]' and [`spearman_matrix`]'s (features first, then the targets).
pub fn most_correlated(names: &[String], m: &[Vec<f64>], n: usize) -> (Vec<String>, Vec<Vec<f64>>) {
    let n_feat = Feature::ALL.len().min(names.len());
    let target = |t: Target| names.iter().position(|c| c == t.column());
    let (ia, ib) = (target(Target::AlphaDeg), target(Target::BetaDeg));
    let score = |i: usize| -> f64 {
        [ia, ib]
            .iter()
            .flatten()
            .filter_map(|&t| m.get(i).and_then(|row| row.get(t)))
            .map(|v| if v.is_finite() { v.abs() } else { 0.0 })
            .fold(0.0, f64::max)
    };
    let mut order: Vec<usize> = (0..n_feat).collect();
    order.sort_by(|&a, &b| score(b).total_cmp(&score(a)));
    let mut keep: Vec<usize> = order.into_iter().take(n).collect();
    keep.sort_unstable();
    keep.extend(n_feat..names.len());
    let sub = keep
        .iter()
        .map(|&i| keep.iter().map(|&j| m[i][j]).collect())
        .collect();
    (keep.iter().map(|&i| names[i].clone()).collect(), sub)
}

/// Spearman matrix of all columns (symmetric, 1 on the diagonal unless a column is constant: NaN).
pub fn spearman_matrix(cols: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let r: Vec<Vec<f64>> = cols.iter().map(|c| ranks(c)).collect();
    let n = cols.len();
    let mut m = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in i..n {
            let v = pearson(&r[i], &r[j]);
            m[i][j] = v;
            m[j][i] = v;
        }
    }
    m
}

/// Sampled Shapley values of `f` at `x` over the model's inputs `features`: for each of
/// `perms` random orders and each background row `z`, inputs switch from `z` to `x` one by one in
/// that order and each switch's change of `f` is credited to the switched input. The values sum to
/// `f(x) - mean_z f(z)` exactly (efficiency), whatever the sample.
pub fn shapley<F: Fn(&FeatureValues) -> f64>(
    f: &F,
    features: &[Feature],
    x: &FeatureValues,
    background: &[FeatureValues],
    perms: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let d = features.len();
    let mut phi = vec![0.0; d];
    let mut order: Vec<usize> = (0..d).collect();
    let mut count = 0usize;
    for _ in 0..perms.max(1) {
        order.shuffle(rng);
        for z in background {
            let mut cur = *z;
            let mut prev = f(&cur);
            for &k in &order {
                let feat = features[k];
                cur.raw[feat.index()] = x.raw[feat.index()];
                let now = f(&cur);
                phi[k] += now - prev;
                prev = now;
            }
            count += 1;
        }
    }
    for p in &mut phi {
        *p /= count.max(1) as f64;
    }
    phi
}

/// Evenly spaced rows of the given flights (at most `n`).
pub fn sample_rows(ds: &Dataset, roles: &[Role], n: usize) -> Vec<FeatureValues> {
    let fl: Vec<_> = ds
        .flights
        .iter()
        .filter(|f| roles.contains(&f.role))
        .collect();
    spread_rows(&fl, n)
        .into_iter()
        .map(|(f, i)| f.features[i])
        .collect()
}

/// Seeded generator for SHAP sampling.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::{Channel, FEATURE_COUNT};

    #[test]
    fn ranks_average_ties() {
        assert_eq!(ranks(&[10.0, 30.0, 20.0, 20.0]), vec![1.0, 4.0, 2.5, 2.5]);
    }

    #[test]
    fn spearman_known_values() {
        let a: Vec<f64> = (0..50).map(|i| i as f64).collect();
        let cube: Vec<f64> = a.iter().map(|x| (x - 20.0).powi(3)).collect();
        let neg: Vec<f64> = a.iter().map(|x| (-x).exp()).collect();
        assert!((spearman(&a, &cube) - 1.0).abs() < 1e-12); // monotone, non-linear
        assert!((spearman(&a, &neg) + 1.0).abs() < 1e-12);
        // d = rank differences (0,0,1,-1,0): rho = 1 - 6*2/(5*24) = 0.9
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        let y = [1.0, 2.0, 4.0, 3.0, 5.0];
        assert!((spearman(&x, &y) - 0.9).abs() < 1e-12);
        assert!(spearman(&x, &[1.0; 5]).is_nan());
        let m = spearman_matrix(&[x.to_vec(), y.to_vec()]);
        assert_eq!(m[0][0], 1.0);
        assert_eq!(m[0][1], m[1][0]);
    }

    #[test]
    fn shapley_of_additive_model_is_exact() {
        // f = 2*a + 3*b, c unused: φ_a = 2(a - mean a_z), φ_b = 3(b - mean b_z), φ_c = 0.
        let fa = Feature::Sensor(Channel::Elevator);
        let fb = Feature::Sensor(Channel::AccelZ);
        let fc = Feature::Sensor(Channel::Rudder);
        let f = |v: &FeatureValues| 2.0 * v.get(fa) as f64 + 3.0 * v.get(fb) as f64;
        let mk = |a: i32, b: i32, c: i32| {
            let mut raw = [0i32; FEATURE_COUNT];
            raw[fa.index()] = a;
            raw[fb.index()] = b;
            raw[fc.index()] = c;
            FeatureValues {
                raw,
                low_speed: false,
                low_ground_speed: false,
                short_lags: 0,
                health: Default::default(),
                filter_flags: 0,
                gyro_disagrees: 0,
                substituted: 0,
                usable: 0,
            }
        };
        let bg = vec![mk(1, 2, 3), mk(3, 0, -1)];
        let x = mk(10, -5, 7);
        let phi = shapley(&f, &[fa, fb, fc], &x, &bg, 5, &mut rng(3));
        assert_eq!(phi, vec![2.0 * (10.0 - 2.0), 3.0 * (-5.0 - 1.0), 0.0]);
        // Interaction: efficiency still holds.
        let g = |v: &FeatureValues| (v.get(fa) * v.get(fb)) as f64;
        let phi = shapley(&g, &[fa, fb, fc], &x, &bg, 3, &mut rng(4));
        let base = bg.iter().map(g).sum::<f64>() / 2.0;
        assert!((phi.iter().sum::<f64>() - (g(&x) - base)).abs() < 1e-9);
    }
}
