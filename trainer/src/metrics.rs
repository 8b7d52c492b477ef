//! Error metrics (degrees): MAE, RMSE, 95th percentile and maximum of |error|.
use serde::{Deserialize, Serialize};

/// An error a flight-control computer would act on if nothing flagged it.
pub const SILENT_ALPHA_DEG: f64 = 2.0;
pub const SILENT_BETA_DEG: f64 = 1.0;

/// Silent frames of one flight: every flag clear (`clear`) while |α error| > [`SILENT_ALPHA_DEG`]
/// or |β error| > [`SILENT_BETA_DEG`]. Returns their count and the longest run of them, frames.
pub fn silent_frames(
    alpha: (&[f64], &[f64]),
    beta: (&[f64], &[f64]),
    clear: impl Fn(usize) -> bool,
) -> (usize, usize) {
    let (mut count, mut run, mut longest) = (0, 0, 0);
    for (i, ((a, ta), (b, tb))) in alpha
        .0
        .iter()
        .zip(alpha.1)
        .zip(beta.0.iter().zip(beta.1))
        .enumerate()
    {
        if clear(i) && ((a - ta).abs() > SILENT_ALPHA_DEG || (b - tb).abs() > SILENT_BETA_DEG) {
            count += 1;
            run += 1;
            longest = usize::max(longest, run);
        } else {
            run = 0;
        }
    }
    (count, longest)
}

#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq)]
#[serde(into = "MetricsJson", from = "MetricsJson")]
pub struct Metrics {
    pub n: usize,
    pub mae: f64,
    pub rmse: f64,
    pub p95: f64,
    pub max: f64,
}

/// [`Metrics`] as JSON: `null` statistics over no frames (an empty band is not an error of 0).
#[derive(Serialize, Deserialize)]
struct MetricsJson {
    n: usize,
    mae: Option<f64>,
    rmse: Option<f64>,
    p95: Option<f64>,
    max: Option<f64>,
}

impl From<Metrics> for MetricsJson {
    fn from(m: Metrics) -> MetricsJson {
        let v = |x: f64| (m.n > 0).then_some(x);
        MetricsJson {
            n: m.n,
            mae: v(m.mae),
            rmse: v(m.rmse),
            p95: v(m.p95),
            max: v(m.max),
        }
    }
}

impl From<MetricsJson> for Metrics {
    fn from(j: MetricsJson) -> Metrics {
        Metrics {
            n: j.n,
            mae: j.mae.unwrap_or(0.0),
            rmse: j.rmse.unwrap_or(0.0),
            p95: j.p95.unwrap_or(0.0),
            max: j.max.unwrap_or(0.0),
        }
    }
}

impl Metrics {
    /// One statistic for a table cell: `{:w.3}`, or `–` over no frames.
    pub fn cell(&self, x: f64, width: usize) -> String {
        if self.n == 0 {
            format!("{:>width$}", "–")
        } else {
            format!("{x:width$.3}")
        }
    }

    pub fn of(pred: &[f64], truth: &[f64]) -> Metrics {
        let mut e: Vec<f64> = pred.iter().zip(truth).map(|(p, t)| (p - t).abs()).collect();
        let n = e.len();
        if n == 0 {
            return Metrics::default();
        }
        let mae = e.iter().sum::<f64>() / n as f64;
        let rmse = (e.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt();
        e.sort_by(f64::total_cmp);
        let p95 = e[((n - 1) as f64 * 0.95).round() as usize];
        Metrics {
            n,
            mae,
            rmse,
            p95,
            max: e[n - 1],
        }
    }
}

/// Metrics per test flight and over all of them, and by regime band of the true angle.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct FlightMetrics {
    pub per_flight: Vec<(String, Metrics)>,
    pub overall: Metrics,
    /// Over every flight's frames, by band of the true angle ([`BandSet`]); empty when not asked for.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bands: Vec<(String, Metrics)>,
}

/// The regime bands of an angle: α by its true value (below 5°, 5–15°, 15–25°, 25° and above), β by
/// its true magnitude (below 2°, 2° and above).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BandSet {
    Alpha,
    Beta,
}

impl BandSet {
    /// (label, lower bound inclusive, upper bound exclusive) of the banded value.
    pub fn bands(self) -> &'static [(&'static str, f64, f64)] {
        match self {
            BandSet::Alpha => &[
                ("α < 5°", f64::NEG_INFINITY, 5.0),
                ("α 5–15°", 5.0, 15.0),
                ("α 15–25°", 15.0, 25.0),
                ("α ≥ 25°", 25.0, f64::INFINITY),
            ],
            BandSet::Beta => &[("|β| < 2°", 0.0, 2.0), ("|β| ≥ 2°", 2.0, f64::INFINITY)],
        }
    }

    fn value(self, truth: f64) -> f64 {
        match self {
            BandSet::Alpha => truth,
            BandSet::Beta => truth.abs(),
        }
    }
}

impl FlightMetrics {
    /// `flights`: (name, predictions, truth).
    pub fn of(flights: &[(String, Vec<f64>, Vec<f64>)]) -> FlightMetrics {
        let per_flight = flights
            .iter()
            .map(|(n, p, t)| (n.clone(), Metrics::of(p, t)))
            .collect();
        let p: Vec<f64> = flights.iter().flat_map(|f| f.1.iter().copied()).collect();
        let t: Vec<f64> = flights.iter().flat_map(|f| f.2.iter().copied()).collect();
        FlightMetrics {
            per_flight,
            overall: Metrics::of(&p, &t),
            bands: Vec::new(),
        }
    }

    /// [`FlightMetrics::of`] with the metrics per band of `set` over all flights.
    pub fn of_banded(flights: &[(String, Vec<f64>, Vec<f64>)], set: BandSet) -> FlightMetrics {
        let mut m = FlightMetrics::of(flights);
        m.bands = set
            .bands()
            .iter()
            .zip(band_metrics(flights, set))
            .map(|(&(label, _, _), b)| (label.to_string(), b))
            .collect();
        m
    }
}

/// Error by flight regime, over every flight's frames: α in the bands below 5°, 5–15°, 15–25° and
/// above 25° of true α, and |β| below and above 2° of true |β|. Each regime's metrics are for the
/// angle named by its key.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Regimes {
    pub alpha_below_5: Metrics,
    pub alpha_5_15: Metrics,
    pub alpha_15_25: Metrics,
    pub alpha_above_25: Metrics,
    pub beta_abs_below_2: Metrics,
    pub beta_abs_above_2: Metrics,
}

impl Regimes {
    /// `alpha`, `beta`: (name, predictions, truth) per flight, in degrees. The bands are
    /// [`BandSet`]'s, named as fields.
    pub fn of(
        alpha: &[(String, Vec<f64>, Vec<f64>)],
        beta: &[(String, Vec<f64>, Vec<f64>)],
    ) -> Regimes {
        let a = band_metrics(alpha, BandSet::Alpha);
        let b = band_metrics(beta, BandSet::Beta);
        let at = |v: &[Metrics], i: usize| v.get(i).copied().unwrap_or_default();
        Regimes {
            alpha_below_5: at(&a, 0),
            alpha_5_15: at(&a, 1),
            alpha_15_25: at(&a, 2),
            alpha_above_25: at(&a, 3),
            beta_abs_below_2: at(&b, 0),
            beta_abs_above_2: at(&b, 1),
        }
    }
}

/// Metrics over every flight's frames per band of `set`, in [`BandSet::bands`] order.
fn band_metrics(flights: &[(String, Vec<f64>, Vec<f64>)], set: BandSet) -> Vec<Metrics> {
    set.bands()
        .iter()
        .map(|&(_, lo, hi)| {
            let (p, t): (Vec<f64>, Vec<f64>) = flights
                .iter()
                .flat_map(|(_, p, t)| p.iter().zip(t))
                .filter(|(_, t)| (lo..hi).contains(&set.value(**t)))
                .map(|(p, t)| (*p, *t))
                .unzip();
            Metrics::of(&p, &t)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_split_frames_by_the_true_angle() {
        let truth = vec![1.0, 6.0, 16.0, 30.0, -3.0];
        let pred = vec![2.0, 6.5, 17.0, 28.0, -3.0];
        let m =
            FlightMetrics::of_banded(&[("f".into(), pred.clone(), truth.clone())], BandSet::Alpha);
        let n: Vec<usize> = m.bands.iter().map(|b| b.1.n).collect();
        assert_eq!(n, vec![2, 1, 1, 1]);
        assert!((m.bands[0].1.mae - 0.5).abs() < 1e-12);
        assert_eq!(m.bands[3].1.mae, 2.0);
        let b = FlightMetrics::of_banded(&[("f".into(), pred, truth)], BandSet::Beta);
        let n: Vec<usize> = b.bands.iter().map(|b| b.1.n).collect();
        assert_eq!(n, vec![1, 4], "|β| bands: only 1.0 is below 2");
    }

    #[test]
    fn metrics_of_known_errors() {
        let t = vec![0.0; 20];
        let p: Vec<f64> = (1..=20).map(|i| i as f64).collect();
        let m = Metrics::of(&p, &t);
        assert_eq!(m.n, 20);
        assert!((m.mae - 10.5).abs() < 1e-12);
        assert!((m.rmse - (2870.0f64 / 20.0).sqrt()).abs() < 1e-12);
        assert_eq!(m.max, 20.0);
        assert_eq!(m.p95, 19.0); // index round(19 * 0.95) = 18
    }
}
