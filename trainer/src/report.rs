//! `trainer report`: every model family of the paper's Table 2 (linear regression, gradient boosting,
//! plain MLP, cascaded MLP float and int8 as deployed) for α and β on the same test flights, seed
//! spread of the neural models, the feature ablation, rendered as markdown.
use crate::baselines::{Baseline, run_baseline};
use crate::data::{Dataset, PAPER_TRAIN_ROWS, Role};
use crate::error::Result;
use crate::features::FeatureSet;
use crate::metrics::{FlightMetrics, Metrics};
use crate::model::{Loss, TrainConfig};
use crate::pipeline::{Answers, Size, Trained, train_angle};
use crate::prep::Angle;
use hil_sim::flight::SAMPLE_HZ;
use serde::{Deserialize, Deserializer, Serialize};
use std::fmt::Write;

/// What `trainer report` runs.
#[derive(Debug, Clone)]
pub struct ReportConfig {
    pub seeds: Vec<u64>,
    pub size: Size,
    pub epochs: usize,
    pub batch: usize,
    pub lr: f64,
    pub gb_rows: usize,
    pub features: FeatureSet,
    /// Feature set of the ablation (None: no ablation).
    pub ablation: Option<FeatureSet>,
    /// The sensor suite the models may read (both feature sets are checked against it).
    pub suite: estimator_core::Suite,
    /// Also the shipped configuration's cascades (its feature set and size, on the `egi` suite, the
    /// report's seeds) and the model-based filter alone: the rows of what ships.
    pub shipped_rows: Option<(FeatureSet, Size, Loss)>,
    /// Where finished rows are kept while the run goes on (JSON lines), so that a killed run
    /// resumes without redoing them (None: no resuming). The caller removes it once the report is
    /// written.
    pub progress_file: Option<std::path::PathBuf>,
}

/// Test metrics of one model for one angle (`int8` only for the deployed cascade).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Entry {
    pub model: String,
    pub angle: Angle,
    pub features: String,
    /// None for deterministic models (linear regression, gradient boosting).
    pub seed: Option<u64>,
    pub float: FlightMetrics,
    pub int8: Option<FlightMetrics>,
    pub seconds: f64,
    /// Answers per test flight (degrees, test order), float and int8, for the pictures.
    #[serde(skip)]
    pub preds: Answers,
    #[serde(skip)]
    pub preds_int8: Option<Answers>,
    /// The same on the out-of-distribution flights (`--ood`; empty without).
    #[serde(skip)]
    pub ood: Answers,
    #[serde(skip)]
    pub ood_int8: Option<Answers>,
}

impl Entry {
    /// The int8 metrics (`int8`; None when this model has no integer path) or the float ones.
    pub fn metrics(&self, int8: bool) -> Option<&FlightMetrics> {
        if int8 {
            self.int8.as_ref()
        } else {
            Some(&self.float)
        }
    }
}

/// Which flights played which part.
#[derive(Debug, Clone, Serialize)]
pub struct Split {
    pub train: Vec<(String, usize)>,
    pub val: Vec<(String, usize)>,
    pub test: Vec<(String, usize)>,
}

impl Split {
    pub fn of(ds: &Dataset) -> Split {
        let f = |r| ds.flights(r).map(|f| (f.name.clone(), f.len())).collect();
        Split {
            train: f(Role::Train),
            val: f(Role::Val),
            test: f(Role::Test),
        }
    }

    /// Rows the models learn from: training plus validation flights.
    pub fn training_rows(&self) -> usize {
        self.train.iter().chain(&self.val).map(|f| f.1).sum()
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub dataset: String,
    pub manifest_sha256: String,
    pub preset: String,
    pub config: String,
    pub epochs: usize,
    pub seeds: Vec<u64>,
    pub features: String,
    /// Sensor suite of the run (`table1` or `egi`).
    pub suite: String,
    pub split: Split,
    pub entries: Vec<Entry>,
}

pub const LINEAR: &str = Baseline::Linear.name();
pub const GB: &str = Baseline::GradientBoosting.name();
pub const MLP: &str = Baseline::Mlp.name();
pub const CASCADE: &str = "Cascaded MLP";
/// The shipped configuration: the hybrid (network over the filter's outputs), `egi` suite.
pub const HYBRID: &str = "Hybrid, shipped configuration";
/// The model-based filter alone (`estimator_core::filter`, `CONFIG`), `egi` suite.
pub const FILTER: &str = "Model-based filter alone";

/// Runs every model. `on_trained` receives the cascades of the first seed (for plots).
pub fn run(
    ds: &Dataset,
    ood: Option<&Dataset>,
    cfg: &ReportConfig,
    mut on_trained: impl FnMut(&Trained, &Trained) -> Result<()>,
    mut log: impl FnMut(&str),
) -> Result<Report> {
    let mut entries = Vec::new();
    let mut progress = Progress::open(cfg.progress_file.as_deref(), &run_key(ds, ood, cfg));
    // Out-of-distribution flights every model also answers on (`--ood`).
    let extra: Vec<&crate::data::Flight> =
        ood.map_or(Vec::new(), |o| o.flights(Role::Test).collect());
    let tc = |seed: u64, label: String| TrainConfig {
        epochs: cfg.epochs,
        batch: cfg.batch,
        lr: cfg.lr,
        seed,
        label,
        progress: true,
        loss: Loss::Mse,
        replicas: None,
        bars: None,
    };
    let fs = &cfg.features;
    for angle in [Angle::Alpha, Angle::Beta] {
        let feats = fs.for_angle(angle);
        for kind in [Baseline::Linear, Baseline::GradientBoosting] {
            let name = kind.name();
            if progress.resume(&mut entries, &mut log, name, angle, &fs.name, None) {
                continue;
            }
            let t0 = std::time::Instant::now();
            let m = run_baseline(
                kind,
                ds,
                angle,
                feats,
                &[],
                &tc(0, String::new()),
                cfg.gb_rows,
                &extra,
            )?;
            let seconds = t0.elapsed().as_secs_f64();
            log(&format!(
                "{} {name}: MAE {:.3} ({seconds:.1} s)",
                angle.symbol(),
                m.metrics.overall.mae
            ));
            entries.push(progress.save(Entry {
                model: name.into(),
                angle,
                features: fs.name.clone(),
                seed: None,
                float: m.metrics,
                int8: None,
                seconds,
                preds: m.preds,
                preds_int8: None,
                ood: m.extra_preds,
                ood_int8: None,
            })?);
        }
        for &seed in &cfg.seeds {
            if progress.resume(&mut entries, &mut log, MLP, angle, &fs.name, Some(seed)) {
                continue;
            }
            let t0 = std::time::Instant::now();
            let m = run_baseline(
                Baseline::Mlp,
                ds,
                angle,
                feats,
                cfg.size.hidden(angle),
                &tc(seed, format!("{} mlp s{seed}", angle.name())),
                cfg.gb_rows,
                &extra,
            )?;
            entries.push(progress.save(Entry {
                model: MLP.into(),
                angle,
                features: fs.name.clone(),
                seed: Some(seed),
                float: m.metrics,
                int8: None,
                seconds: t0.elapsed().as_secs_f64(),
                preds: m.preds,
                preds_int8: None,
                ood: m.extra_preds,
                ood_int8: None,
            })?);
        }
    }
    let mut sets = vec![fs];
    if let Some(a) = &cfg.ablation {
        sets.push(a);
    }
    for set in sets {
        for (k, &seed) in cfg.seeds.iter().enumerate() {
            let mut pair = Vec::new();
            for angle in [Angle::Alpha, Angle::Beta] {
                if progress.resume(
                    &mut entries,
                    &mut log,
                    CASCADE,
                    angle,
                    &set.name,
                    Some(seed),
                ) {
                    continue;
                }
                let t0 = std::time::Instant::now();
                let t = train_angle(
                    ds,
                    angle,
                    set.for_angle(angle),
                    cfg.size,
                    &tc(
                        seed,
                        format!("{} cascade {} s{seed}", angle.name(), set.name),
                    ),
                );
                let e = trained_entry(CASCADE, &set.name, seed, &t, t0, &extra);
                log(&trained_line("cascade", &e));
                entries.push(progress.save(e)?);
                pair.push(t);
            }
            // (A resumed pair drew its pictures in the run that trained it.)
            if let (0, true, [a, b]) = (k, std::ptr::eq(set, fs), pair.as_slice()) {
                on_trained(a, b)?;
            }
        }
    }
    if let Some((hfs, hsize, hloss)) = &cfg.shipped_rows {
        for &seed in &cfg.seeds {
            for angle in [Angle::Alpha, Angle::Beta] {
                if progress.resume(&mut entries, &mut log, HYBRID, angle, &hfs.name, Some(seed)) {
                    continue;
                }
                let t0 = std::time::Instant::now();
                let t = train_angle(
                    ds,
                    angle,
                    hfs.for_angle(angle),
                    *hsize,
                    &TrainConfig {
                        loss: *hloss,
                        ..tc(seed, format!("{} hybrid s{seed}", angle.name()))
                    },
                );
                let e = trained_entry(HYBRID, &hfs.name, seed, &t, t0, &extra);
                log(&trained_line("hybrid", &e));
                entries.push(progress.save(e)?);
            }
        }
        entries.extend(filter_entries(ds, &extra));
    }
    Ok(Report {
        dataset: ds.dir.display().to_string(),
        manifest_sha256: ds.manifest_sha256.clone(),
        preset: ds.preset.clone(),
        config: cfg.size.name().into(),
        epochs: cfg.epochs,
        seeds: cfg.seeds.clone(),
        features: fs.name.clone(),
        suite: cfg.suite.name().into(),
        split: Split::of(ds),
        entries,
    })
}

/// The row of a trained cascade (or hybrid): its test metrics and answers, float and int8, and its
/// answers on the OOD flights (`extra`).
fn trained_entry(
    model: &str,
    features: &str,
    seed: u64,
    t: &Trained,
    started: std::time::Instant,
    extra: &[&crate::data::Flight],
) -> Entry {
    let seconds = started.elapsed().as_secs_f64();
    let (ood, ood_int8) = crate::pipeline::answers(t, extra);
    let answers = |k: usize| -> Answers {
        t.series
            .iter()
            .map(|x| (x.0.clone(), if k == 2 { x.2.clone() } else { x.3.clone() }))
            .collect()
    };
    Entry {
        model: model.into(),
        angle: t.angle,
        features: features.into(),
        seed: Some(seed),
        float: t.float_test.clone(),
        int8: Some(t.int_test.clone()),
        seconds,
        preds: answers(2),
        preds_int8: Some(answers(3)),
        ood,
        ood_int8: Some(ood_int8),
    }
}

/// The log line of a trained row.
fn trained_line(kind: &str, e: &Entry) -> String {
    format!(
        "{} {kind} [{}] seed {}: float MAE {:.3}, int8 MAE {:.3} ({:.1} s)",
        e.angle.symbol(),
        e.features,
        e.seed.unwrap_or(0),
        e.float.overall.mae,
        e.int8.as_ref().map_or(f64::NAN, |m| m.overall.mae),
        e.seconds
    )
}

/// What makes two report runs the same run (their finished rows interchangeable): the datasets and
/// every setting but the seed list, so that adding seeds reuses the rows already trained.
fn run_key(ds: &Dataset, ood: Option<&Dataset>, cfg: &ReportConfig) -> String {
    format!(
        "{}|{}|{}|{}|{}|{}|{}|{}|{}|{}|{}",
        ds.manifest_sha256,
        ood.map_or("", |o| o.manifest_sha256.as_str()),
        cfg.size.name(),
        cfg.epochs,
        cfg.batch,
        cfg.lr,
        cfg.gb_rows,
        cfg.features.name,
        cfg.ablation.as_ref().map_or("", |a| a.name.as_str()),
        cfg.suite.name(),
        cfg.shipped_rows
            .as_ref()
            .map_or(String::new(), |(f, z, l)| {
                format!("{}:{}:{}", f.name, z.name(), l.name())
            }),
    )
}

/// One finished row as kept in the progress file.
#[derive(Serialize, Deserialize)]
struct Saved {
    key: String,
    entry: Entry,
    preds: Answers,
    preds_int8: Option<Answers>,
    ood: Answers,
    ood_int8: Option<Answers>,
}

/// The finished rows of a run (see [`ReportConfig::progress_file`]).
struct Progress {
    path: Option<std::path::PathBuf>,
    key: String,
    done: Vec<Entry>,
}

impl Progress {
    /// Reads the rows of the same run (same key) left by a killed one; other lines are ignored.
    fn open(path: Option<&std::path::Path>, key: &str) -> Progress {
        let done = path
            .and_then(|p| std::fs::read_to_string(p).ok())
            .map(|text| {
                text.lines()
                    .filter_map(|l| serde_json::from_str::<Saved>(l).ok())
                    .filter(|s| s.key == key)
                    .map(|s| Entry {
                        preds: s.preds,
                        preds_int8: s.preds_int8,
                        ood: s.ood,
                        ood_int8: s.ood_int8,
                        ..s.entry
                    })
                    .collect()
            })
            .unwrap_or_default();
        Progress {
            path: path.map(std::path::Path::to_path_buf),
            key: key.to_string(),
            done,
        }
    }

    /// Puts the finished row of this run into `entries`, if the killed run had it (saying so).
    fn resume(
        &mut self,
        entries: &mut Vec<Entry>,
        log: &mut impl FnMut(&str),
        model: &str,
        angle: Angle,
        features: &str,
        seed: Option<u64>,
    ) -> bool {
        let Some(e) = self.take(model, angle, features, seed) else {
            return false;
        };
        let seed = seed.map_or(String::new(), |s| format!(" seed {s}"));
        log(&format!(
            "{} {model} [{features}]{seed}: resumed",
            angle.symbol()
        ));
        entries.push(e);
        true
    }

    /// A finished row of this run, if the killed run had it.
    fn take(
        &mut self,
        model: &str,
        angle: Angle,
        features: &str,
        seed: Option<u64>,
    ) -> Option<Entry> {
        let i = self.done.iter().position(|e| {
            e.model == model && e.angle == angle && e.features == features && e.seed == seed
        })?;
        Some(self.done.swap_remove(i))
    }

    /// Appends a finished row to the file and hands it back.
    fn save(&mut self, entry: Entry) -> Result<Entry> {
        let Some(path) = &self.path else {
            return Ok(entry);
        };
        let saved = Saved {
            key: self.key.clone(),
            preds: entry.preds.clone(),
            preds_int8: entry.preds_int8.clone(),
            ood: entry.ood.clone(),
            ood_int8: entry.ood_int8.clone(),
            entry,
        };
        let mut line =
            serde_json::to_string(&saved).map_err(|e| crate::Error::Plot(e.to_string()))?;
        line.push('\n');
        use std::io::Write as _;
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .and_then(|mut f| f.write_all(line.as_bytes()))
            .map_err(crate::error::io("write", &path))?;
        Ok(Entry {
            preds: saved.preds,
            preds_int8: saved.preds_int8,
            ood: saved.ood,
            ood_int8: saved.ood_int8,
            ..saved.entry
        })
    }
}

/// The model-based filter alone on the test flights (and `extra` ones), frame by frame as the
/// firmware runs it.
fn filter_entries(ds: &Dataset, extra: &[&crate::data::Flight]) -> Vec<Entry> {
    use crate::data::Target;
    let t0 = std::time::Instant::now();
    let run = |fl: &crate::data::Flight| {
        crate::filter_eval::degrees(&crate::filter_eval::run_flight(
            estimator_core::filter::CONFIG,
            &fl.frames,
        ))
    };
    let mut a = Vec::new();
    let mut b = Vec::new();
    for fl in ds.flights(Role::Test) {
        let (pa, pb) = run(fl);
        a.push((fl.name.clone(), pa, fl.truth(Target::AlphaDeg).to_vec()));
        b.push((fl.name.clone(), pb, fl.truth(Target::BetaDeg).to_vec()));
    }
    let (mut oa, mut ob) = (Vec::new(), Vec::new());
    for fl in extra {
        let (pa, pb) = run(fl);
        oa.push((fl.name.clone(), pa));
        ob.push((fl.name.clone(), pb));
    }
    let seconds = t0.elapsed().as_secs_f64();
    [(Angle::Alpha, a, oa), (Angle::Beta, b, ob)]
        .into_iter()
        .map(|(angle, fl, o)| Entry {
            model: FILTER.into(),
            angle,
            features: "filter".into(),
            seed: None,
            float: FlightMetrics::of_banded(&fl, angle.bands()),
            int8: None,
            seconds,
            preds: fl.into_iter().map(|(n, p, _)| (n, p)).collect(),
            preds_int8: None,
            ood: o,
            ood_int8: None,
        })
        .collect()
}

/// The cases of the `ood` preset in table order (`nominal` first: the twins).
const OOD_CASES: [&str; 8] = [
    "nominal",
    "mass-low",
    "mass-high",
    "wind-25",
    "turbulence-plus",
    "gust-15",
    "gps-outage",
    "imu-stuck",
];

impl Report {
    /// The out-of-distribution section: per Table 2 row and angle, MAE over both profiles' flights
    /// of each case (mean over seeds) and its ratio to the in-distribution twins' (`nominal`).
    pub fn ood_markdown(&self, ood: &Dataset) -> String {
        use crate::data::Target;
        let truth: std::collections::HashMap<&str, (&[f64], &[f64])> = ood
            .flights(Role::Test)
            .map(|f| {
                (
                    f.name.as_str(),
                    (f.truth(Target::AlphaDeg), f.truth(Target::BetaDeg)),
                )
            })
            .collect();
        // MAE of one entry's answers over the flights of `case`.
        let case_mae = |answers: &Answers, angle: Angle, case: &str| -> Option<f64> {
            let (mut sum, mut n) = (0.0, 0usize);
            for (name, p) in answers {
                if crate::ood::case_and_profile(name).0 != case {
                    continue;
                }
                let (ta, tb) = truth.get(name.as_str())?;
                let t = if angle == Angle::Alpha { ta } else { tb };
                for (p, t) in p.iter().zip(t.iter()) {
                    sum += (p - t).abs();
                    n += 1;
                }
            }
            (n > 0).then(|| sum / n as f64)
        };
        let mut s = format!(
            "\n## Out of distribution (`--ood {}`)\n\n\
             Every row trained above, answering on the `ood` preset's flights (docs/results/ood.md \
             for the cases): MAE over the case's flights on both profiles, mean over seeds, and in \
             brackets its ratio to the same row on the in-distribution twins (`nominal`). These \
             rows have no flags of their own; `trainer ood` scores the shipped estimator with its \
             flags.\n",
            ood.dir.display()
        );
        for angle in [Angle::Alpha, Angle::Beta] {
            let _ = writeln!(s, "\n### {} MAE, degrees\n", angle.symbol());
            let _ = writeln!(s, "| model | {} |", OOD_CASES.join(" | "));
            let _ = writeln!(s, "|---|{}", "---|".repeat(OOD_CASES.len()));
            for (model, int8, label) in [
                (LINEAR, false, "Linear regression"),
                (GB, false, "Gradient boosting"),
                (MLP, false, "Plain MLP"),
                (CASCADE, false, "Cascaded MLP (float)"),
                (CASCADE, true, "Cascaded MLP (int8)"),
                (HYBRID, false, "Hybrid, shipped configuration (float)"),
                (HYBRID, true, "Hybrid, shipped configuration (int8)"),
                (FILTER, false, "Model-based filter alone"),
            ] {
                let es: Vec<&Entry> = self.select(model, angle, &self.features);
                let per_case: Vec<Option<f64>> = OOD_CASES
                    .iter()
                    .map(|c| {
                        let v: Vec<f64> = es
                            .iter()
                            .filter_map(|e| {
                                let a = if int8 { e.ood_int8.as_ref()? } else { &e.ood };
                                case_mae(a, angle, c)
                            })
                            .collect();
                        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
                    })
                    .collect();
                let Some(Some(nominal)) = per_case.first().copied() else {
                    continue;
                };
                let cells: Vec<String> = per_case
                    .iter()
                    .map(|m| match m {
                        Some(m) => format!("{m:.3} (×{:.2})", m / nominal),
                        None => "–".into(),
                    })
                    .collect();
                let _ = writeln!(s, "| {label} | {} |", cells.join(" | "));
            }
        }
        s
    }
}

/// Bin width of the error-by-α picture: true α in 2.5° steps.
const ALPHA_BIN_DEG: f64 = 2.5;
/// The error-by-dynamic-pressure picture has about this many bins over the test flights' range
/// (an F-16 flies 3–60 kPa, a light single 1–4: no one width fits every aircraft).
const QBAR_BINS: f64 = 12.0;

/// The round width (1, 2 or 5 × a power of ten) at or above `raw`; 1 for a range that is empty.
pub fn round_bin_width(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let decade = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .find(|m| m * decade >= raw * (1.0 - 1e-9))
        .unwrap_or(10.0);
    step * decade
}

/// Binned mean |error| of `pred` against `truth`, by `x` in bins of `width`: (bin centre, MAE,
/// frames) for every bin that has frames.
pub fn binned_mae(x: &[f64], pred: &[f64], truth: &[f64], width: f64) -> Vec<(f64, f64, usize)> {
    let mut bins: std::collections::BTreeMap<i64, (f64, usize)> = Default::default();
    for ((x, p), t) in x.iter().zip(pred).zip(truth) {
        if !(x.is_finite() && p.is_finite() && t.is_finite()) {
            continue;
        }
        let b = bins.entry((x / width).floor() as i64).or_default();
        b.0 += (p - t).abs();
        b.1 += 1;
    }
    bins.into_iter()
        .map(|(k, (sum, n))| ((k as f64 + 0.5) * width, sum / n as f64, n))
        .collect()
}

impl Report {
    /// The rows drawn in the pictures: each model family's first seed (float), and the deployed
    /// int8 cascade; (label, α answers, β answers) per test flight.
    fn picture_rows(&self) -> Vec<(String, &Answers, &Answers)> {
        let mut rows = Vec::new();
        for (model, int8) in [
            (LINEAR, false),
            (GB, false),
            (MLP, false),
            (CASCADE, false),
            (CASCADE, true),
            (HYBRID, true),
            (FILTER, false),
        ] {
            let first = |a: Angle| {
                self.select(model, a, &self.features)
                    .into_iter()
                    .min_by_key(|e| e.seed)
                    .and_then(|e| {
                        if int8 {
                            e.preds_int8.as_ref()
                        } else {
                            Some(&e.preds)
                        }
                    })
                    .filter(|p| !p.is_empty())
            };
            if let (Some(a), Some(b)) = (first(Angle::Alpha), first(Angle::Beta)) {
                let kind = match (model, int8) {
                    (CASCADE | HYBRID, true) => " int8",
                    (CASCADE, false) => " float",
                    _ => "",
                };
                rows.push((format!("{model}{kind}"), a, b));
            }
        }
        rows
    }

    /// Writes the Table 2 pictures into `out` and returns their file names:
    /// * `table2_estimates_alpha.png`, `table2_estimates_beta.png`: estimate and truth over the
    ///   high-α test flight (else the first), one panel per row;
    /// * `table2_error_by_alpha.png`, `table2_error_by_qbar.png`: MAE of α and β binned by true α
    ///   and by true dynamic pressure, one line per row, and the test frames per bin.
    pub fn pictures(&self, ds: &Dataset, out: &std::path::Path) -> Result<Vec<String>> {
        use crate::data::Target;
        use crate::plots::{Series, line_panels};
        let rows = self.picture_rows();
        let test: Vec<&crate::data::Flight> = ds.flights(Role::Test).collect();
        let mut written = Vec::new();
        if rows.is_empty() || test.is_empty() {
            return Ok(written);
        }
        let k = test
            .iter()
            .position(|f| f.name.contains("high-alpha"))
            .unwrap_or(0);
        let fl = test[k];
        for (angle, target, file) in [
            (Angle::Alpha, Target::AlphaDeg, "table2_estimates_alpha.png"),
            (Angle::Beta, Target::BetaDeg, "table2_estimates_beta.png"),
        ] {
            let truth: Vec<(f64, f64)> = fl
                .time_s
                .iter()
                .zip(fl.truth(target))
                .map(|(t, v)| (*t, *v))
                .collect();
            let est: Vec<Vec<(f64, f64)>> = rows
                .iter()
                .map(|(_, a, b)| {
                    let p = if angle == Angle::Alpha { a } else { b };
                    p.get(k)
                        .map(|(_, v)| fl.time_s.iter().copied().zip(v.iter().copied()).collect())
                        .unwrap_or_default()
                })
                .collect();
            let panels: Vec<_> = rows
                .iter()
                .zip(&est)
                .map(|((label, _, _), e)| {
                    (
                        format!("{label}: {}", fl.name),
                        "time, s",
                        if angle == Angle::Alpha {
                            "α, deg"
                        } else {
                            "β, deg"
                        },
                        false,
                        vec![
                            Series {
                                name: "truth".into(),
                                points: &truth,
                            },
                            Series {
                                name: "estimate".into(),
                                points: e,
                            },
                        ],
                    )
                })
                .collect();
            line_panels(&out.join(file), &panels, 480, 380)?;
            written.push(file.to_string());
        }
        // Error by regime over every test frame.
        let concat = |f: &dyn Fn(&crate::data::Flight) -> &[f64]| -> Vec<f64> {
            test.iter().flat_map(|fl| f(fl).iter().copied()).collect()
        };
        let ta = concat(&|f| f.truth(Target::AlphaDeg));
        let tb = concat(&|f| f.truth(Target::BetaDeg));
        let qbar_kpa: Vec<f64> = concat(&|f| &f.qbar_pa).iter().map(|q| q / 1000.0).collect();
        let (q_lo, q_hi) = qbar_kpa
            .iter()
            .filter(|q| q.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &q| {
                (lo.min(q), hi.max(q))
            });
        let qbar_bin_kpa = round_bin_width((q_hi - q_lo) / QBAR_BINS);
        let flat =
            |p: &Answers| -> Vec<f64> { p.iter().flat_map(|(_, v)| v.iter().copied()).collect() };
        for (xs, width, xl, file) in [
            (
                &ta,
                ALPHA_BIN_DEG,
                "true α, deg",
                "table2_error_by_alpha.png",
            ),
            (
                &qbar_kpa,
                qbar_bin_kpa,
                "true dynamic pressure, kPa",
                "table2_error_by_qbar.png",
            ),
        ] {
            // Per row, MAE by bin of one angle's answers against its truth.
            let binned = |angle: Angle| -> Vec<Vec<(f64, f64)>> {
                rows.iter()
                    .map(|(_, a, b)| {
                        let (p, t) = if angle == Angle::Alpha {
                            (a, &ta)
                        } else {
                            (b, &tb)
                        };
                        binned_mae(xs, &flat(p), t, width)
                            .into_iter()
                            .map(|(x, m, _)| (x, m))
                            .collect()
                    })
                    .collect()
            };
            let (mae_a, mae_b) = (binned(Angle::Alpha), binned(Angle::Beta));
            let counts: Vec<(f64, f64)> = binned_mae(xs, &ta, &ta, width)
                .into_iter()
                .map(|(x, _, n)| (x, n as f64))
                .collect();
            fn series<'a>(labels: &[String], v: &'a [Vec<(f64, f64)>]) -> Vec<Series<'a>> {
                labels
                    .iter()
                    .zip(v)
                    .map(|(label, pts)| Series {
                        name: label.clone(),
                        points: pts,
                    })
                    .collect()
            }
            let labels: Vec<String> = rows.iter().map(|r| r.0.clone()).collect();
            line_panels(
                &out.join(file),
                &[
                    (
                        "α MAE by bin".to_string(),
                        xl,
                        "α MAE, deg",
                        true,
                        series(&labels, &mae_a),
                    ),
                    (
                        "β MAE by bin".to_string(),
                        xl,
                        "β MAE, deg",
                        true,
                        series(&labels, &mae_b),
                    ),
                    (
                        "test frames per bin".to_string(),
                        xl,
                        "frames",
                        true,
                        vec![Series {
                            name: "frames".into(),
                            points: &counts,
                        }],
                    ),
                ],
                560,
                420,
            )?;
            written.push(file.to_string());
        }
        Ok(written)
    }
}

/// Mean and spread (half the max − min range) of values.
pub fn mean_spread(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (mean, (hi - lo) / 2.0)
}

/// Element-wise mean of metrics over seeds (n kept).
pub fn mean_metrics(ms: &[Metrics]) -> Metrics {
    let k = ms.len().max(1) as f64;
    let s = |f: fn(&Metrics) -> f64| ms.iter().map(f).sum::<f64>() / k;
    Metrics {
        n: ms.first().map(|m| m.n).unwrap_or(0),
        mae: s(|m| m.mae),
        rmse: s(|m| m.rmse),
        p95: s(|m| m.p95),
        max: s(|m| m.max),
    }
}

/// A Table-2 row: model label and, per angle, the metrics (averaged over seeds) of one test flight or
/// of all of them (see [`Report::rows`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub label: String,
    /// The model family (`LINEAR`, `GB`, `MLP`, `CASCADE`).
    pub model: &'static str,
    pub alpha: Metrics,
    pub beta: Metrics,
    /// Per regime band of the true angle (overall rows only), averaged over seeds like the rest.
    pub alpha_bands: Vec<(String, Metrics)>,
    pub beta_bands: Vec<(String, Metrics)>,
}

/// The paper's Table 2 (test-set MAE, degrees, α and β) for a model family.
pub fn paper_mae(model: &str) -> Option<(f64, f64)> {
    match model {
        LINEAR => Some((2.538, 0.486)),
        GB => Some((1.178, 0.448)),
        MLP => Some((0.897, 0.396)),
        CASCADE => Some((0.534, 0.247)),
        _ => None,
    }
}

/// Band-wise [`mean_metrics`] of several band lists with the same labels.
fn mean_bands(lists: &[&Vec<(String, Metrics)>]) -> Vec<(String, Metrics)> {
    let Some(first) = lists.first() else {
        return Vec::new();
    };
    first
        .iter()
        .enumerate()
        .map(|(i, (label, _))| {
            let ms: Vec<Metrics> = lists.iter().filter_map(|l| l.get(i).map(|b| b.1)).collect();
            (label.clone(), mean_metrics(&ms))
        })
        .collect()
}

impl Report {
    fn select(&self, model: &str, angle: Angle, features: &str) -> Vec<&Entry> {
        self.entries
            .iter()
            .filter(|e| {
                e.model == model
                    && e.angle == angle
                    && (e.features == features || model == HYBRID || model == FILTER)
            })
            .collect()
    }

    /// Table-2 rows (float, and int8 for the cascade) for `flight` (None: overall), main feature set.
    pub fn rows(&self, flight: Option<&str>) -> Vec<Row> {
        let of_flight = |m: &FlightMetrics| -> Metrics {
            match flight {
                None => m.overall,
                Some(f) => m
                    .per_flight
                    .iter()
                    .find(|(n, _)| n == f)
                    .map(|x| x.1)
                    .unwrap_or_default(),
            }
        };
        let mut rows = Vec::new();
        for (model, int8) in [
            (LINEAR, false),
            (GB, false),
            (MLP, false),
            (CASCADE, false),
            (CASCADE, true),
            (HYBRID, false),
            (HYBRID, true),
            (FILTER, false),
        ] {
            let chosen = |a: Angle| -> Vec<&FlightMetrics> {
                self.select(model, a, &self.features)
                    .into_iter()
                    .filter_map(|e| e.metrics(int8))
                    .collect()
            };
            let agg = |a: Angle| {
                let ms: Vec<Metrics> = chosen(a).into_iter().map(of_flight).collect();
                (mean_metrics(&ms), ms.len())
            };
            let bands = |a: Angle| -> Vec<(String, Metrics)> {
                if flight.is_some() {
                    return Vec::new();
                }
                let lists: Vec<&Vec<(String, Metrics)>> =
                    chosen(a).into_iter().map(|m| &m.bands).collect();
                mean_bands(&lists)
            };
            let (a, na) = agg(Angle::Alpha);
            let (b, _) = agg(Angle::Beta);
            if na == 0 {
                continue;
            }
            let seeds = if model == LINEAR || model == GB || model == FILTER {
                String::new()
            } else {
                format!(", mean of {na} seed{}", if na == 1 { "" } else { "s" })
            };
            let kind = match (model, int8) {
                (CASCADE | HYBRID, true) => " (int8, deployed)",
                (CASCADE | HYBRID, false) => " (float)",
                _ => "",
            };
            rows.push(Row {
                label: format!("{model}{kind}{seeds}"),
                model,
                alpha: a,
                beta: b,
                alpha_bands: bands(Angle::Alpha),
                beta_bands: bands(Angle::Beta),
            });
        }
        rows
    }

    /// Model labels by overall MAE, best first, per angle.
    pub fn ranking(&self, angle: Angle) -> Vec<(String, f64)> {
        let mut r: Vec<(String, f64)> = self
            .rows(None)
            .into_iter()
            .map(|row| {
                let m = match angle {
                    Angle::Alpha => row.alpha.mae,
                    Angle::Beta => row.beta.mae,
                };
                (row.label, m)
            })
            .collect();
        r.sort_by(|a, b| a.1.total_cmp(&b.1));
        r
    }

    /// Overall MAE per seed of a model/angle/feature set (`int8`: the deployed cascade).
    pub fn seed_maes(&self, model: &str, angle: Angle, features: &str, int8: bool) -> Vec<f64> {
        self.select(model, angle, features)
            .iter()
            .filter_map(|e| e.metrics(int8).map(|m| m.overall.mae))
            .collect()
    }

    /// The markdown report (training.md). `command` and `machine` are free text; `ablation` names the
    /// ablation feature set (None: no ablation section); `bench` adds the epoch-time benchmark of
    /// `trainer bench-epoch`. Warns when the dataset or the network sizes are not the paper's.
    pub fn markdown(
        &self,
        command: &str,
        machine: &str,
        ablation: Option<&str>,
        bench: Option<&BenchEpoch>,
    ) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Training results: Table 2 (generated by `trainer report`)\n"
        );
        let rows = self.split.training_rows();
        if self.preset != "paper" && rows < PAPER_TRAIN_ROWS {
            let _ = writeln!(
                s,
                "> **Not the paper experiment.** Dataset preset `{}`: {rows} training rows ({:.1} min of \
                 flight at {SAMPLE_HZ} Hz) vs the paper's 288 000 (4 h). These figures check the pipeline and \
                 compare the model families on one small split; rerun \
                 `trainer report --data out/data/paper --config paper` for the paper-scale Table 2.\n",
                self.preset,
                rows as f64 / f64::from(SAMPLE_HZ) / 60.0
            );
        }
        if let Some(size) = Size::parse(&self.config).filter(|&z| z != Size::Paper) {
            let _ = writeln!(
                s,
                "> **`{}` networks** (α {}, β {} per part), not the paper's sizes: `--config paper` \
                 trains α {} and β {} per part.\n",
                size.name(),
                widths(size.hidden(Angle::Alpha)),
                widths(size.hidden(Angle::Beta)),
                widths(Size::Paper.hidden(Angle::Alpha)),
                widths(Size::Paper.hidden(Angle::Beta)),
            );
        }
        let _ = writeln!(
            s,
            "Dataset `{}` (preset {}, manifest sha256 `{}`), configuration **{}**, {} epochs, \
             seeds {:?}, features `{}`, sensor suite `{}`. Every model is trained on the same \
             training flights and scored on the same test flights; errors in degrees.\n",
            self.dataset,
            self.preset,
            self.manifest_sha256,
            self.config,
            self.epochs,
            self.seeds,
            self.features,
            self.suite
        );
        let _ = writeln!(s, "Command: `{command}`  \nMachine: {machine}\n");
        let _ = writeln!(s, "## Split (by flight)\n");
        for (name, fl) in [
            ("train", &self.split.train),
            (
                "validation (held-out training flights, model selection)",
                &self.split.val,
            ),
            ("test (unseen until evaluation)", &self.split.test),
        ] {
            let rows: usize = fl.iter().map(|f| f.1).sum();
            let names: Vec<&str> = fl.iter().map(|f| f.0.as_str()).collect();
            let _ = writeln!(
                s,
                "- **{name}**: {} flights, {rows} rows: {}",
                fl.len(),
                names.join(", ")
            );
        }
        s.push('\n');
        let header = "| model | α MAE | α RMSE | α p95 | α max | β MAE | β RMSE | β p95 | β max |\n|---|---|---|---|---|---|---|---|---|\n";
        let table = |s: &mut String, rows: &[Row]| {
            s.push_str(header);
            for r in rows {
                let _ = writeln!(
                    s,
                    "| {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
                    r.label,
                    r.alpha.mae,
                    r.alpha.rmse,
                    r.alpha.p95,
                    r.alpha.max,
                    r.beta.mae,
                    r.beta.rmse,
                    r.beta.p95,
                    r.beta.max
                );
            }
            s.push('\n');
        };
        let n_test: usize = self.split.test.iter().map(|f| f.1).sum();
        let _ = writeln!(
            s,
            "## Table 2: all test flights ({} flights, {n_test} frames)\n",
            self.split.test.len()
        );
        let overall = self.rows(None);
        table(&mut s, &overall);
        let _ = writeln!(
            s,
            "### Beside the paper (Table 2 of Karali et al. 2023: MAE on its own test flights)\n"
        );
        s.push_str("| model | α MAE | paper α | β MAE | paper β |\n|---|---|---|---|---|\n");
        for r in &overall {
            let (pa, pb) = paper_mae(r.model)
                .map_or(("–".to_string(), "–".to_string()), |(a, b)| {
                    (format!("{a:.3}"), format!("{b:.3}"))
                });
            let _ = writeln!(
                s,
                "| {} | {:.3} | {pa} | {:.3} | {pb} |",
                r.label, r.alpha.mae, r.beta.mae
            );
        }
        s.push('\n');
        if let Some(first) = overall.first().filter(|r| !r.alpha_bands.is_empty()) {
            let _ = writeln!(
                s,
                "### By regime (all test flights; MAE, frames per band in the header)\n"
            );
            let head: Vec<String> = first
                .alpha_bands
                .iter()
                .chain(&first.beta_bands)
                .map(|(l, m)| format!("{} ({} frames)", l.replace('|', "\\|"), m.n))
                .collect();
            let _ = writeln!(s, "| model | {} |", head.join(" | "));
            let _ = writeln!(s, "|---|{}", "---|".repeat(head.len()));
            for r in &overall {
                let cells: Vec<String> = r
                    .alpha_bands
                    .iter()
                    .chain(&r.beta_bands)
                    .map(|(_, m)| {
                        if m.n == 0 {
                            "–".to_string()
                        } else {
                            format!("{:.3}", m.mae)
                        }
                    })
                    .collect();
                let _ = writeln!(s, "| {} | {} |", r.label, cells.join(" | "));
            }
            s.push('\n');
        }
        for (name, n) in &self.split.test {
            let _ = writeln!(s, "### Test flight `{name}` ({n} frames)\n");
            table(&mut s, &self.rows(Some(name)));
        }
        let _ = writeln!(s, "## Ranking (overall MAE, best first)\n");
        for a in [Angle::Alpha, Angle::Beta] {
            let r: Vec<String> = self
                .ranking(a)
                .iter()
                .map(|(l, m)| format!("{l} {m:.3}"))
                .collect();
            let _ = writeln!(s, "- **{}**: {}", a.symbol(), r.join(" < "));
        }
        let _ = writeln!(
            s,
            "\n## Seed spread (overall MAE, mean ± half range over seeds {:?})\n",
            self.seeds
        );
        s.push_str("| model | α MAE | β MAE | per seed α | per seed β |\n|---|---|---|---|---|\n");
        let mut sets = vec![self.features.clone()];
        if let Some(a) = ablation {
            sets.push(a.to_string());
        }
        let mut lines: Vec<(&str, String, bool)> = Vec::new();
        for set in &sets {
            for (model, int8) in [(MLP, false), (CASCADE, false), (CASCADE, true)] {
                lines.push((model, set.clone(), int8));
            }
        }
        if let Some(h) = self.entries.iter().find(|e| e.model == HYBRID) {
            lines.push((HYBRID, h.features.clone(), false));
            lines.push((HYBRID, h.features.clone(), true));
        }
        for (model, set, int8) in &lines {
            let (model, set, int8) = (*model, set, *int8);
            {
                let a = self.seed_maes(model, Angle::Alpha, set, int8);
                let b = self.seed_maes(model, Angle::Beta, set, int8);
                if a.is_empty() {
                    continue;
                }
                let (am, asp) = mean_spread(&a);
                let (bm, bsp) = mean_spread(&b);
                let fmt = |v: &[f64]| {
                    v.iter()
                        .map(|x| format!("{x:.3}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                let _ = writeln!(
                    s,
                    "| {model}{} [{set}] | {am:.3} ± {asp:.3} | {bm:.3} ± {bsp:.3} | {} | {} |",
                    if int8 {
                        " int8"
                    } else if model == CASCADE || model == HYBRID {
                        " float"
                    } else {
                        ""
                    },
                    fmt(&a),
                    fmt(&b)
                );
            }
        }
        if let Some(abl) = ablation {
            let _ = writeln!(
                s,
                "\n## Ablation: `{}` vs `{abl}` features (cascade, overall MAE, mean ± half range over seeds)\n",
                self.features
            );
            s.push_str(
                "| features | α float | α int8 | β float | β int8 |\n|---|---|---|---|---|\n",
            );
            for set in [self.features.as_str(), abl] {
                let c = |a, i| {
                    let (m, sp) = mean_spread(&self.seed_maes(CASCADE, a, set, i));
                    format!("{m:.3} ± {sp:.3}")
                };
                let _ = writeln!(
                    s,
                    "| {set} | {} | {} | {} | {} |",
                    c(Angle::Alpha, false),
                    c(Angle::Alpha, true),
                    c(Angle::Beta, false),
                    c(Angle::Beta, true)
                );
            }
            for a in [Angle::Alpha, Angle::Beta] {
                let (base, _) = mean_spread(&self.seed_maes(CASCADE, a, &self.features, true));
                let (with, _) = mean_spread(&self.seed_maes(CASCADE, a, abl, true));
                let _ = writeln!(
                    s,
                    "\n{} int8 MAE change with `{abl}`: {:+.1} %",
                    a.symbol(),
                    (with - base) / base * 100.0
                );
            }
        }
        s.push_str("\n## Plots (first seed, main feature set)\n\n");
        s.push_str(
            "Learning curves (train/val MSE of both heads per epoch, paper Fig. 9):\n\n\
             ![learning curves](training_learning_curves.png)\n\n",
        );
        s.push_str(
            "Predicted vs truth on the first two test flights (paper Fig. 11–12):\n\n\
             ![α test time series](training_test_timeseries_alpha.png)\n\n\
             ![β test time series](training_test_timeseries_beta.png)\n",
        );
        s.push_str(
            "\nEvery row on the high-α test flight (first seed; one panel per row):\n\n\
             ![α estimates per row](table2_estimates_alpha.png)\n\n\
             ![β estimates per row](table2_estimates_beta.png)\n\n\
             Error by regime over every test frame: MAE binned by true α (2.5° bins) and by true \
             dynamic pressure (about twelve bins of a round width over the test flights' range), with the test frames per bin, so the thin corners of the \
             envelope show:\n\n\
             ![error by α](table2_error_by_alpha.png)\n\n\
             ![error by dynamic pressure](table2_error_by_qbar.png)\n",
        );
        if let Some(b) = bench {
            let _ = write!(
                s,
                "\n## Benchmark: paper-size α cascade epoch time\n\n`{}` on {}: **{:.2} s per epoch** \
                 (mean of epochs 2..{}, first epoch {:.2} s) for {} training rows + a {}-row validation \
                 pass, α cascade 2 × {}-{}-1, batch {}{}; ≈ {:.1} s per epoch scaled \
                 linearly to the paper's 288 000 rows.{}\n",
                b.command,
                b.machine,
                b.mean_epoch_s,
                b.epochs,
                b.first_epoch_s,
                b.train_rows,
                b.val_rows,
                b.n_in,
                widths(Size::Paper.hidden(Angle::Alpha)),
                b.batch,
                if b.replicas > 1 {
                    format!(" split over {} replicas", b.replicas)
                } else {
                    String::new()
                },
                b.per_epoch_288k_s,
                if b.best_epoch > 0 {
                    format!(
                        " Its best validation epoch is epoch {} of {}, reached after **{:.1} min** of training (all {} epochs: {:.1} min).",
                        b.best_epoch,
                        b.epochs,
                        b.time_to_best_s / 60.0,
                        b.epochs,
                        b.epoch_s.iter().sum::<f64>() / 60.0
                    )
                } else {
                    String::new()
                },
            );
        }
        s
    }
}

/// Hidden widths as `512-256-128`.
fn widths(h: &[usize]) -> String {
    h.iter()
        .map(|n| n.to_string())
        .collect::<Vec<_>>()
        .join("-")
}

/// What `trainer bench-epoch` measured (its JSON file; fields in alphabetical order, as the file has
/// always had them). Fields missing from the file read as "?", NaN or 0; a null number as NaN (how
/// serde_json writes NaN).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct BenchEpoch {
    pub batch: usize,
    /// The epoch (1-based) with the lowest validation loss; 0 in files from before it was recorded.
    pub best_epoch: usize,
    /// That lowest validation loss (both heads, as `train` selects); NaN in files from before it
    /// was recorded.
    #[serde(deserialize_with = "nan_if_null")]
    pub best_val_loss: f64,
    pub command: String,
    pub dataset: String,
    pub epoch_s: Vec<f64>,
    pub epochs: usize,
    #[serde(deserialize_with = "nan_if_null")]
    pub first_epoch_s: f64,
    pub machine: String,
    /// Mean of epochs 2.. (the first is warm-up).
    #[serde(deserialize_with = "nan_if_null")]
    pub mean_epoch_s: f64,
    pub n_in: usize,
    /// `mean_epoch_s` scaled linearly to [`PAPER_TRAIN_ROWS`] training rows.
    #[serde(deserialize_with = "nan_if_null")]
    pub per_epoch_288k_s: f64,
    /// Training time up to and including the best validation epoch, s.
    #[serde(deserialize_with = "nan_if_null")]
    pub time_to_best_s: f64,
    /// Replicas each batch was split over; 1 in files from before the split existed.
    pub replicas: usize,
    pub train_rows: usize,
    pub val_rows: usize,
}

impl Default for BenchEpoch {
    fn default() -> BenchEpoch {
        BenchEpoch {
            batch: 0,
            best_epoch: 0,
            best_val_loss: f64::NAN,
            command: "?".into(),
            dataset: "?".into(),
            epoch_s: Vec::new(),
            epochs: 0,
            first_epoch_s: f64::NAN,
            machine: "?".into(),
            mean_epoch_s: f64::NAN,
            n_in: 0,
            per_epoch_288k_s: f64::NAN,
            time_to_best_s: f64::NAN,
            replicas: 1,
            train_rows: 0,
            val_rows: 0,
        }
    }
}

fn nan_if_null<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

#[cfg(test)]
mod tests {
    #[test]
    fn dynamic_pressure_bins_have_a_round_width() {
        // F-16 test flights (3-60 kPa) keep their 5 kPa bins; a light single's 1-4 kPa gets 0.5.
        assert_eq!(super::round_bin_width(57.0 / 12.0), 5.0);
        assert_eq!(super::round_bin_width(3.0 / 12.0), 0.5);
        assert_eq!(super::round_bin_width(0.2), 0.2);
        assert_eq!(super::round_bin_width(0.0), 1.0);
    }

    use super::*;

    fn fm(name: &str, mae: f64) -> FlightMetrics {
        let m = Metrics {
            n: 10,
            mae,
            rmse: mae * 2.0,
            p95: mae * 3.0,
            max: mae * 4.0,
        };
        FlightMetrics {
            per_flight: vec![(name.into(), m)],
            overall: m,
            bands: vec![
                ("low".into(), m),
                (
                    "high".into(),
                    Metrics {
                        mae: mae * 5.0,
                        ..m
                    },
                ),
            ],
        }
    }

    fn entry(model: &str, angle: Angle, seed: Option<u64>, mae: f64, int8: Option<f64>) -> Entry {
        Entry {
            model: model.into(),
            angle,
            features: "table1".into(),
            seed,
            float: fm("t1", mae),
            int8: int8.map(|x| fm("t1", x)),
            seconds: 0.0,
            preds: Vec::new(),
            preds_int8: None,
            ood: Vec::new(),
            ood_int8: None,
        }
    }

    fn report() -> Report {
        let mut entries = Vec::new();
        for (a, k) in [(Angle::Alpha, 1.0), (Angle::Beta, 2.0)] {
            entries.push(entry(LINEAR, a, None, 0.5 * k, None));
            entries.push(entry(GB, a, None, 0.2 * k, None));
            entries.push(entry(MLP, a, Some(1), 0.3 * k, None));
            entries.push(entry(MLP, a, Some(2), 0.1 * k, None));
            entries.push(entry(CASCADE, a, Some(1), 0.15 * k, Some(0.16 * k)));
            entries.push(entry(CASCADE, a, Some(2), 0.25 * k, Some(0.26 * k)));
        }
        Report {
            dataset: "d".into(),
            manifest_sha256: "h".into(),
            preset: "ci".into(),
            config: "small".into(),
            epochs: 1,
            seeds: vec![1, 2],
            features: "table1".into(),
            suite: "table1".into(),
            split: Split {
                train: vec![("a".into(), 5)],
                val: vec![("b".into(), 5)],
                test: vec![("t1".into(), 10)],
            },
            entries,
        }
    }

    #[test]
    fn rows_average_seeds_and_keep_int8_separate() {
        let r = report();
        let rows = r.rows(None);
        assert_eq!(rows.len(), 5);
        assert_eq!(rows[0].label, LINEAR);
        assert!((rows[2].alpha.mae - 0.2).abs() < 1e-12); // MLP mean of 0.3, 0.1
        assert!((rows[3].alpha.mae - 0.2).abs() < 1e-12); // cascade float mean of 0.15, 0.25
        assert!((rows[4].beta.mae - 0.42).abs() < 1e-12); // cascade int8 β mean of 0.32, 0.52
        assert!((rows[4].beta.max - 1.68).abs() < 1e-12);
        // Regime bands average over seeds like the rest; per-flight rows carry none.
        assert!((rows[2].alpha_bands[1].1.mae - 1.0).abs() < 1e-12); // MLP mean of 1.5, 0.5
        assert_eq!(rows[2].alpha_bands[1].0, "high");
        let t1 = r.rows(Some("t1"));
        assert!(t1.iter().all(|row| row.alpha_bands.is_empty()));
        assert!(
            t1.iter()
                .zip(&rows)
                .all(|(a, b)| a.alpha == b.alpha && a.beta == b.beta && a.label == b.label)
        );
        assert_eq!(r.rows(Some("nope"))[0].alpha.n, 0);
    }

    #[test]
    fn progress_keeps_finished_rows_of_the_same_run_only() {
        let path =
            std::env::temp_dir().join(format!("report-progress-{}.jsonl", std::process::id()));
        let _ = std::fs::remove_file(&path);
        let mut p = Progress::open(Some(&path), "run A");
        let mut e = entry(MLP, Angle::Beta, Some(2), 0.3, None);
        e.preds = vec![("t1".into(), vec![1.0, 2.0])];
        e.ood_int8 = Some(vec![("o".into(), vec![3.0])]);
        let back = p.save(e.clone()).unwrap();
        assert_eq!(back.preds, e.preds);
        p.save(entry(GB, Angle::Alpha, None, 0.2, None)).unwrap();
        // A killed run's rows come back, answers included; another run's key sees none.
        let mut q = Progress::open(Some(&path), "run A");
        let r = q.take(MLP, Angle::Beta, "table1", Some(2)).unwrap();
        assert_eq!(
            (r.preds.clone(), r.ood_int8.clone()),
            (e.preds.clone(), e.ood_int8.clone())
        );
        assert!((r.float.overall.mae - 0.3).abs() < 1e-12);
        assert!(
            q.take(MLP, Angle::Beta, "table1", Some(2)).is_none(),
            "taken once"
        );
        assert!(q.take(MLP, Angle::Beta, "table1", Some(3)).is_none());
        assert!(q.take(GB, Angle::Alpha, "table1", None).is_some());
        let mut other = Progress::open(Some(&path), "run B");
        assert!(other.take(GB, Angle::Alpha, "table1", None).is_none());
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn binned_mae_counts_and_averages_per_bin() {
        let x = [0.1, 0.2, 2.6, -0.1, f64::NAN];
        let p = [1.0, 3.0, 5.0, 0.0, 1.0];
        let t = [0.0, 0.0, 4.0, 1.0, 0.0];
        let b = binned_mae(&x, &p, &t, 2.5);
        assert_eq!(b, vec![(-1.25, 1.0, 1), (1.25, 2.0, 2), (3.75, 1.0, 1)]);
    }

    #[test]
    fn ranking_and_spread() {
        let r = report();
        let rank = r.ranking(Angle::Alpha);
        assert!(rank.windows(2).all(|w| w[0].1 <= w[1].1));
        assert_eq!(rank[0].0, GB);
        assert_eq!(rank.last().unwrap().0, LINEAR);
        let (m, sp) = mean_spread(&r.seed_maes(MLP, Angle::Beta, "table1", false));
        assert!((m - 0.4).abs() < 1e-12 && (sp - 0.2).abs() < 1e-12);
        let md = r.markdown("cmd", "machine", None, None);
        assert!(md.contains("| Gradient boosting | 0.200 | 0.400 | 0.600 | 0.800 | 0.400 |"));
        assert!(md.contains("0.200 ± 0.100"));
        // The paper's figures beside ours, and the regime table.
        assert!(
            md.contains("| Gradient boosting | 0.200 | 1.178 | 0.400 | 0.448 |"),
            "{md}"
        );
        assert!(md.contains(
            "| model | low (10 frames) | high (10 frames) | low (10 frames) | high (10 frames) |"
        ));
        assert!(md.contains("| Gradient boosting | 0.200 | 1.000 | 0.400 | 2.000 |"));
    }
}

/// Where a `trainer features` run comes from, for the head of `features.md`.
#[derive(Debug, Clone)]
pub struct FeaturesHead {
    pub dataset: String,
    pub preset: String,
    pub manifest_sha256: String,
    pub command: String,
    pub machine: String,
}

/// `features.md`: the Spearman table of every candidate feature against the air-data targets
/// (`m`: the matrix over `names`, candidates first, then the four targets), the matrix among the
/// features, then `shap` (the SHAP section).
pub fn features_markdown(
    head: &FeaturesHead,
    names: &[String],
    m: &[Vec<f64>],
    n_rows: usize,
    shap: &str,
) -> String {
    let nf = estimator_core::Feature::ALL.len();
    let mut md = String::from("# Feature analysis (generated by `trainer features`)\n\n");
    let _ = writeln!(
        md,
        "Dataset `{}` (preset {}, manifest sha256 `{}`); command `{}`; machine: {}.\n",
        head.dataset, head.preset, head.manifest_sha256, head.command, head.machine
    );
    let _ = writeln!(
        md,
        "## Spearman rank correlation with the air data\n\n{n_rows} rows evenly sampled from the \
         training and validation flights (never the test flights). Every candidate of \
         `estimator_core::Feature::ALL` (sensed channels of every suite + derived features, SI values as the models \
         see them); the air-data columns are targets only: the feature parser refuses them as inputs \
         (`trainer::features::parse_feature`, test `air_data_can_never_become_an_input`). \
         Full matrix (features and targets among themselves): `features_spearman.csv`, heatmap below.\n"
    );
    md.push_str(
        "| feature | alpha_deg | beta_deg | w_aero_mps | v_aero_mps |\n|---|---|---|---|---|\n",
    );
    let at = |i: usize, j: usize| m.get(i).and_then(|r| r.get(j)).copied().unwrap_or(f64::NAN);
    let name = |i: usize| names.get(i).map_or("?", |n| n.as_str());
    let mut order: Vec<usize> = (0..nf).collect();
    order.sort_by(|&a, &b| {
        let k = |i: usize| at(i, nf).abs().max(at(i, nf + 1).abs());
        k(b).total_cmp(&k(a))
    });
    for i in order {
        let _ = writeln!(
            md,
            "| {} | {:+.3} | {:+.3} | {:+.3} | {:+.3} |",
            name(i),
            at(i, nf),
            at(i, nf + 1),
            at(i, nf + 2),
            at(i, nf + 3)
        );
    }
    md.push_str("\n(sorted by max(|ρ α|, |ρ β|); NaN: constant column in this dataset)\n\n![Spearman heatmap](features_spearman.png)\n\n");
    md.push_str("### Among the features\n\n| | ");
    md.push_str(
        &names
            .iter()
            .take(nf)
            .cloned()
            .collect::<Vec<_>>()
            .join(" | "),
    );
    md.push_str(" |\n|---|");
    md.push_str(&"---|".repeat(nf));
    md.push('\n');
    for i in 0..nf {
        let vals: Vec<String> = (0..nf).map(|j| format!("{:+.2}", at(i, j))).collect();
        let _ = writeln!(md, "| {} | {} |", name(i), vals.join(" | "));
    }
    md.push('\n');
    md.push_str(shap);
    md
}

/// One model's mean |SHAP| per input, and the bar chart drawn of it.
#[derive(Debug, Clone)]
pub struct ShapChart {
    pub name: String,
    pub items: Vec<(String, f64)>,
    pub png: String,
}

/// The SHAP section of `features.md` (paper Fig. 8).
pub fn shap_markdown(
    provenance: &str,
    explained: usize,
    background: usize,
    permutations: usize,
    seed: u64,
    charts: &[ShapChart],
) -> String {
    let mut md = String::from("## SHAP: mean |Shapley value| per input (paper Fig. 8)\n\n");
    let _ = writeln!(
        md,
        "Model: the compiled-in int8 cascades (`estimator_core::model::{{ALPHA, BETA}}`, \
         `AngleNet::run`, bit-exact with the firmware), provenance: {provenance}. Sampled Shapley values: \
         {explained} test rows explained, {background} background rows from the training flights, {permutations} random feature \
         orders per row (seed {seed}); an input's value is switched from the background row to the \
         explained row and the change of the predicted angle (degrees) is credited to it. Values sum \
         exactly to prediction − mean background prediction.\n"
    );
    for c in charts {
        let mut sorted = c.items.clone();
        sorted.sort_by(|x, y| y.1.total_cmp(&x.1));
        let _ = writeln!(
            md,
            "### {}\n\n| input | mean abs SHAP (deg) |\n|---|---|",
            c.name
        );
        for (n, v) in &sorted {
            let _ = writeln!(md, "| {n} | {v:.4} |");
        }
        let _ = writeln!(md, "\n![{} SHAP]({})\n", c.name, c.png);
    }
    md
}
