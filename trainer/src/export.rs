//! Writes the generated model, its test vectors, learning curves and a JSON summary.
use crate::data::{Dataset, PAPER_TRAIN_ROWS, Role};
use crate::error::Result;
use crate::metrics::FlightMetrics;
use crate::pipeline::Trained;
use crate::plots::{Series, line_panels};
use crate::quant::{QCascade, format_vectors, generate, vectors};
use estimator_core::{Channel, SensorFrame, Suite};
use sha2::{Digest, Sha256};
use std::fmt::Write;
use std::path::Path;

use hil_sim::dataset::git_rev;

fn metrics_line(m: &FlightMetrics) -> String {
    let o = m.overall;
    format!(
        "MAE {:.3} RMSE {:.3} p95 {:.3} max {:.3} deg (n={})",
        o.mae, o.rmse, o.p95, o.max, o.n
    )
}

/// The lines of a PROVENANCE text ([`provenance`]) before its split line: the dataset, each
/// `--extra-data` one and a small-data warning, joined by "; " (what a report names as the
/// model's training data).
pub fn provenance_data(provenance: &str) -> String {
    provenance
        .lines()
        .take_while(|l| !l.starts_with(SPLIT_LINE))
        .collect::<Vec<_>>()
        .join("; ")
}

/// The manifest sha256 of the dataset a PROVENANCE text ([`provenance`]) names on its first line,
/// the one the model was trained with (`dataset: DIR (preset P), manifest sha256 H`): the 64 hex
/// digits after the line's last `manifest sha256 `, or `None` where there are none (a path that
/// holds the words does not fool it).
pub fn provenance_manifest(provenance: &str) -> Option<&str> {
    let (_, rest) = provenance.lines().next()?.rsplit_once("manifest sha256 ")?;
    let sha = rest.split_whitespace().next()?;
    (sha.len() == 64 && sha.bytes().all(|b| b.is_ascii_hexdigit())).then_some(sha)
}

/// The first PROVENANCE line after the data lines.
pub const SPLIT_LINE: &str = "split by flight:";

/// PROVENANCE text of a generated model.
pub fn provenance(
    ds: &Dataset,
    seed: u64,
    command: &str,
    feature_set: &str,
    suite: Suite,
    alpha: &Trained,
    beta: &Trained,
) -> String {
    let mut s = String::new();
    let preset = &ds.preset;
    let _ = writeln!(
        s,
        "dataset: {} (preset {preset}), manifest sha256 {}",
        ds.dir.display(),
        ds.manifest_sha256
    );
    for e in &ds.extra {
        let _ = writeln!(
            s,
            "plus the {} training flights of {}",
            e.flights,
            e.describe()
        );
    }
    if let Some(t) = ds.gyro_bias_twins {
        let _ = writeln!(
            s,
            "plus {} gyro-bias twins of the training flights (seed {}){}",
            t.flights,
            t.seed,
            t.angles.describe()
        );
    }
    let rows = ds.training_rows();
    if preset == "ci" || rows < PAPER_TRAIN_ROWS {
        let _ = writeln!(
            s,
            "WARNING: trained on {rows} rows (preset {preset}), less than the paper's 4 h \
             ({PAPER_TRAIN_ROWS} rows): a pipeline check, not a flight-quality model"
        );
    }
    let _ = writeln!(
        s,
        "{SPLIT_LINE} train {} flights / {} rows, validation {} / {}, test {} / {}",
        ds.flights(Role::Train).count(),
        ds.rows(Role::Train),
        ds.flights(Role::Val).count(),
        ds.rows(Role::Val),
        ds.flights(Role::Test).count(),
        ds.rows(Role::Test)
    );
    for t in &ds.test_from {
        let _ = writeln!(s, "test flights: the {} of {}", t.flights, t.describe());
    }
    let _ = writeln!(
        s,
        "seed: {seed}; features: {feature_set}; sensor suite: {}",
        suite.name()
    );
    let _ = writeln!(s, "command: {command}");
    let _ = writeln!(s, "git: {}", git_rev());
    for t in [alpha, beta] {
        let _ = writeln!(
            s,
            "{}: hidden {} per part, {} params, best epoch {}/{}; test float {}; test int8 {}",
            t.angle.name(),
            t.q.widths(),
            t.q.params(),
            t.curves.best_epoch + 1,
            t.curves.train.len(),
            metrics_line(&t.float_test),
            metrics_line(&t.int_test)
        );
    }
    s
}

/// Frames for the test vectors, as a sender of `suite` delivers them: `segments` evenly spaced runs
/// of `len` consecutive test-flight frames (each starting on an empty history, so the first second
/// exercises the short-history path), plus each of the suite's channels driven to the ends of its
/// wire range (exercises envelope clamps and feature saturation).
pub fn vector_frames(
    ds: &Dataset,
    suite: Suite,
    segments: usize,
    len: usize,
) -> Vec<(bool, SensorFrame)> {
    let all: Vec<SensorFrame> = ds
        .flights(Role::Test)
        .flat_map(|f| f.frames.iter())
        .map(|f| f.restricted_to(suite))
        .collect();
    let step = (all.len() / segments.max(1)).max(len);
    let mut out: Vec<(bool, SensorFrame)> = Vec::new();
    for start in (0..all.len().saturating_sub(len))
        .step_by(step)
        .take(segments)
    {
        for (k, f) in all.iter().skip(start).take(len).enumerate() {
            out.push((k == 0, *f));
        }
    }
    // Extreme raw values, each on a fresh history.
    if let Some((_, base)) = out.first().copied() {
        for c in Channel::ALL.into_iter().filter(|c| suite.carries(*c)) {
            let (lo, hi) = c.raw_range();
            for v in [lo, hi, 0] {
                let mut f = base;
                // A sub-sampled channel's six 120 Hz values too (an `egi120` frame carries them).
                f.set_everywhere(c, v);
                out.push((true, f));
            }
        }
    }
    out
}

pub fn sha256_hex(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The smallest suite that feeds both networks, the format of their test vectors: a Table 1
/// model's vectors stay in the Table 1 format whatever the dataset carries.
pub fn vector_suite(alpha: &QCascade, beta: &QCascade) -> Suite {
    let sources = [alpha, beta]
        .iter()
        .flat_map(|q| q.prep.features.iter())
        .fold(0, |m, f| m | f.sources());
    Suite::covering(sources).unwrap_or(Suite::Egi120)
}

/// Writes weights.rs and the test vectors; returns the weights file's SHA-256.
pub fn write_model(
    ds: &Dataset,
    alpha: &QCascade,
    beta: &QCascade,
    provenance: &str,
    weights_out: &Path,
    vectors_out: &Path,
) -> Result<String> {
    let src = generate(alpha, beta, provenance);
    let hash = sha256_hex(&src);
    let suite = vector_suite(alpha, beta);
    let vs = vectors(alpha, beta, &vector_frames(ds, suite, 8, 40));
    let header = format!(
        "@generated by `trainer train`: integer test vectors for the model in {}\n\
         weights_sha256 {hash}\n\
         Expected outputs computed by the trainer's independent i64 reference (trainer/src/quant.rs).\n\
         Lines are sequences of consecutive frames; reset = 1 starts a sequence with an empty History.\n\
         For each line: frame = SensorFrame {{ seq, time_ms, raw, valid, sub }} (sub: the sub-samples of an egi120 line, else none); values = state.next(&frame) with one estimator_core::FeatureState::new(true) per run (delta history and air-data filter);\n\
         ALPHA.run(&values) == (w_aero_mms, alpha_mdeg, alpha_clamped) and BETA.run(&values) == (v_aero_mms, beta_mdeg, beta_clamped).",
        weights_out.display()
    );
    let vectors = format_vectors(&vs, suite, &header);
    crate::files::write_together(&[(weights_out, &src), (vectors_out, &vectors)])?;
    Ok(hash)
}

/// Learning curves: per angle, train/val loss of both heads per epoch (log scale).
pub fn plot_curves(path: &Path, ts: &[&Trained]) -> Result<()> {
    let mut owned = Vec::new();
    for t in ts {
        let pts = |v: &Vec<[f64; 2]>, k: usize| -> Vec<(f64, f64)> {
            v.iter()
                .enumerate()
                .map(|(e, l)| ((e + 1) as f64, l[k]))
                .collect()
        };
        owned.push((
            t.angle,
            [
                pts(&t.curves.train, 0),
                pts(&t.curves.val, 0),
                pts(&t.curves.train, 1),
                pts(&t.curves.val, 1),
            ],
        ));
    }
    let panels: Vec<_> = owned
        .iter()
        .map(|(a, p)| {
            let mid = match a {
                crate::prep::Angle::Alpha => "w_aero",
                crate::prep::Angle::Beta => "v_aero",
            };
            (
                format!("{} cascade: training loss (normalised; --loss)", a.symbol()),
                "epoch",
                "loss",
                true,
                vec![
                    Series {
                        name: format!("train {mid}"),
                        points: &p[0],
                    },
                    Series {
                        name: format!("val {mid}"),
                        points: &p[1],
                    },
                    Series {
                        name: format!("train {}", a.name()),
                        points: &p[2],
                    },
                    Series {
                        name: format!("val {}", a.name()),
                        points: &p[3],
                    },
                ],
            )
        })
        .collect();
    line_panels(path, &panels, 640, 420)
}

/// Predicted vs truth time series of the first `max_flights` test flights.
pub fn plot_series(path: &Path, ds: &Dataset, ts: &[&Trained], max_flights: usize) -> Result<()> {
    let times: Vec<&Vec<f64>> = ds.flights(Role::Test).map(|f| &f.time_s).collect();
    let mut owned = Vec::new();
    for t in ts {
        for (k, (name, truth, pf, pi)) in t.series.iter().enumerate().take(max_flights) {
            let tt = times[k];
            let z = |v: &Vec<f64>| -> Vec<(f64, f64)> {
                tt.iter().copied().zip(v.iter().copied()).collect()
            };
            owned.push((
                format!("{} {name}", t.angle.symbol()),
                [z(truth), z(pf), z(pi)],
            ));
        }
    }
    let panels: Vec<_> = owned
        .iter()
        .map(|(title, p)| {
            (
                title.clone(),
                "time (s)",
                "deg",
                false,
                vec![
                    Series {
                        name: "truth".into(),
                        points: &p[0],
                    },
                    Series {
                        name: "float".into(),
                        points: &p[1],
                    },
                    Series {
                        name: "int8 (deployed)".into(),
                        points: &p[2],
                    },
                ],
            )
        })
        .collect();
    line_panels(path, &panels, 700, 380)
}

#[cfg(test)]
mod tests {
    use super::provenance_manifest;

    #[test]
    fn the_manifest_is_the_first_line_s_last_64_hex_digits() {
        let sha = "0123456789abcdef".repeat(4);
        let line = |dir: &str, tail: &str| {
            format!("dataset: {dir} (preset large), manifest sha256 {tail}\nsplit by flight: …")
        };
        assert_eq!(
            provenance_manifest(&line("out/data/large", &sha)),
            Some(sha.as_str())
        );
        // A path holding the words, or text after the digits, does not change what is read.
        let odd = line("out/manifest sha256 x", &format!("{sha} (reused)"));
        assert_eq!(provenance_manifest(&odd), Some(sha.as_str()));
        // No digits, too few, or not hex: no manifest.
        for tail in ["", "abc", &"g".repeat(64)] {
            assert_eq!(provenance_manifest(&line("d", tail)), None, "{tail}");
        }
        assert_eq!(provenance_manifest(""), None);
    }
}
