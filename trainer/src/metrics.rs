//! Error metrics (degrees): MAE, RMSE, 95th percentile and maximum of |error|.
use serde::Serialize;

#[derive(Debug, Clone, Copy, Default, Serialize, PartialEq)]
pub struct Metrics {
    pub n: usize,
    pub mae: f64,
    pub rmse: f64,
    pub p95: f64,
    pub max: f64,
}

impl Metrics {
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

/// Metrics per test flight and over all of them.
#[derive(Debug, Clone, Default, Serialize)]
pub struct FlightMetrics {
    pub per_flight: Vec<(String, Metrics)>,
    pub overall: Metrics,
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
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
