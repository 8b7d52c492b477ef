use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use trainer::data::Dataset;
use trainer::export::{plot_curves, plot_series, provenance, write_model};
use trainer::features::FeatureSet;
use trainer::metrics::FlightMetrics;
use trainer::model::TrainConfig;
use trainer::pipeline::{Size, eval_shipped, train_angle};
use trainer::prep::Angle;

#[derive(Parser)]
#[command(about = "Train, quantize, export and evaluate the synthetic air data estimator")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(clap::Args, Clone)]
struct TrainArgs {
    /// Dataset directory (manifest.json + CSVs from `hil-sim generate`).
    #[arg(long)]
    data: PathBuf,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Network sizes: small (CI) or paper.
    #[arg(long, default_value = "small")]
    config: String,
    /// Epochs (default: 40 small, 30 paper).
    #[arg(long)]
    epochs: Option<usize>,
    #[arg(long, default_value_t = 256)]
    batch: usize,
    #[arg(long, default_value_t = 1e-3)]
    lr: f64,
    /// Input features: table1, physics (Table 1 + specific force/ρV² + Mach proxy), or
    /// "alpha=a,b,...;beta=c,d,..." with names of estimator_core::Feature.
    #[arg(long, default_value = "table1")]
    features: String,
    /// Fraction of training flights held out (by flight) for validation.
    #[arg(long, default_value_t = 0.15)]
    val_fraction: f64,
}

#[derive(Subcommand)]
enum Cmd {
    /// Train both cascades, quantize, write weights.rs + test vectors + plots.
    Train {
        #[command(flatten)]
        args: TrainArgs,
        /// Output directory for plots and summary.json.
        #[arg(long)]
        out: PathBuf,
        #[arg(long, default_value = "estimator-core/src/model/weights.rs")]
        weights_out: PathBuf,
        #[arg(long, default_value = "estimator-core/tests/vectors/shipped.txt")]
        vectors_out: PathBuf,
        /// Do not write weights.rs / vectors (training and plots only).
        #[arg(long)]
        no_export: bool,
    },
    /// Table 2 baselines (linear regression, gradient boosting, plain MLP) on the test flights.
    Baselines {
        #[command(flatten)]
        args: TrainArgs,
        /// Training rows (evenly subsampled) for gradient boosting.
        #[arg(long, default_value_t = 40_000)]
        gb_rows: usize,
    },
    /// Evaluate the compiled-in model (Estimator::shipped) on the test flights.
    Eval {
        #[arg(long)]
        data: PathBuf,
        /// Print exactly one JSON object.
        #[arg(long)]
        json: bool,
    },
}

fn print_metrics(label: &str, m: &FlightMetrics) {
    for (name, x) in &m.per_flight {
        println!(
            "  {label:<6} {name:<24} MAE {:7.3}  RMSE {:7.3}  p95 {:7.3}  max {:7.3}  (n={})",
            x.mae, x.rmse, x.p95, x.max, x.n
        );
    }
    let o = m.overall;
    println!(
        "  {label:<6} {:<24} MAE {:7.3}  RMSE {:7.3}  p95 {:7.3}  max {:7.3}  (n={})",
        "OVERALL", o.mae, o.rmse, o.p95, o.max, o.n
    );
}

fn cmd_train(
    args: &TrainArgs,
    out: &PathBuf,
    weights_out: &Path,
    vectors_out: &Path,
    no_export: bool,
) -> Result<()> {
    let size = Size::parse(&args.config).context("--config must be small or paper")?;
    let fs = FeatureSet::parse(&args.features)?;
    let ds = Dataset::load(&args.data, args.val_fraction)
        .with_context(|| format!("loading dataset {}", args.data.display()))?;
    eprintln!(
        "dataset {}: train {} rows, val {} rows, test {} rows",
        args.data.display(),
        ds.rows(trainer::data::Role::Train),
        ds.rows(trainer::data::Role::Val),
        ds.rows(trainer::data::Role::Test)
    );
    if ds.rows(trainer::data::Role::Val) == 0 {
        bail!("no validation flight: the dataset needs at least two training flights");
    }
    let epochs = args.epochs.unwrap_or(match size {
        Size::Small => 40,
        Size::Paper => 30,
    });
    let cfg = |a: Angle| TrainConfig {
        epochs,
        batch: args.batch,
        lr: args.lr,
        seed: args.seed,
        label: a.name().into(),
        progress: true,
    };
    let alpha = train_angle(&ds, Angle::Alpha, &fs.alpha, size, &cfg(Angle::Alpha));
    let beta = train_angle(&ds, Angle::Beta, &fs.beta, size, &cfg(Angle::Beta));
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    plot_curves(&out.join("learning_curves.png"), &[&alpha, &beta])?;
    plot_series(&out.join("test_timeseries.png"), &ds, &[&alpha, &beta], 2)?;
    for t in [&alpha, &beta] {
        println!("{} ({}): float", t.angle.symbol(), t.q.widths());
        print_metrics("float", &t.float_test);
        print_metrics("int8", &t.int_test);
        let ep: f64 = t.curves.epoch_s.iter().sum::<f64>() / t.curves.epoch_s.len().max(1) as f64;
        println!(
            "  mean epoch time {ep:.2} s, best epoch {}",
            t.curves.best_epoch + 1
        );
    }
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let prov = provenance(&ds, args.seed, &command, &fs.name, &alpha, &beta);
    let summary = serde_json::json!({
        "seed": args.seed, "config": size.name(), "features": fs.name, "epochs": epochs,
        "alpha": {"float": alpha.float_test, "int8": alpha.int_test, "curves": alpha.curves},
        "beta": {"float": beta.float_test, "int8": beta.int_test, "curves": beta.curves},
        "provenance": prov,
    });
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    if !no_export {
        let hash = write_model(&ds, &alpha, &beta, &prov, weights_out, vectors_out)?;
        println!(
            "wrote {} (sha256 {hash}) and {}",
            weights_out.display(),
            vectors_out.display()
        );
    }
    Ok(())
}

fn cmd_eval(data: &Path, json: bool) -> Result<()> {
    let ds =
        Dataset::load(data, 0.15).with_context(|| format!("loading dataset {}", data.display()))?;
    let Some(prov) = trainer::pipeline::shipped_provenance() else {
        bail!(
            "this build has no compiled-in model: run `trainer train` first (it writes estimator-core/src/model/weights.rs)"
        );
    };
    let e = eval_shipped(&ds);
    if json {
        let v = serde_json::json!({
            "model": "shipped (Estimator::shipped, int8)",
            "dataset": data.display().to_string(),
            "manifest_sha256": ds.manifest_sha256,
            "alpha": e.alpha, "beta": e.beta,
            "flagged": e.flagged.iter().map(|(n, h, o)| serde_json::json!({"flight": n, "not_usable": h, "out_of_envelope": o})).collect::<Vec<_>>(),
            "provenance": prov,
        });
        println!("{}", serde_json::to_string(&v)?);
    } else {
        println!("compiled-in model:\n{prov}");
        println!("α (deg):");
        print_metrics("int8", &e.alpha);
        println!("β (deg):");
        print_metrics("int8", &e.beta);
        for (n, h, o) in &e.flagged {
            println!("  {n}: {h} frames not usable (held/no estimate), {o} out of envelope");
        }
    }
    Ok(())
}

fn cmd_baselines(args: &TrainArgs, gb_rows: usize) -> Result<()> {
    use trainer::baselines::{Baseline, run_baseline};
    let size = Size::parse(&args.config).context("--config must be small or paper")?;
    let fs = FeatureSet::parse(&args.features)?;
    let ds = Dataset::load(&args.data, args.val_fraction)
        .with_context(|| format!("loading dataset {}", args.data.display()))?;
    let epochs = args.epochs.unwrap_or(40);
    for angle in [Angle::Alpha, Angle::Beta] {
        let feats = match angle {
            Angle::Alpha => &fs.alpha,
            Angle::Beta => &fs.beta,
        };
        for kind in [Baseline::Linear, Baseline::GradientBoosting, Baseline::Mlp] {
            let cfg = TrainConfig {
                epochs,
                batch: args.batch,
                lr: args.lr,
                seed: args.seed,
                label: format!("{} mlp", angle.name()),
                progress: false,
            };
            let t0 = std::time::Instant::now();
            let m = run_baseline(kind, &ds, angle, feats, size.hidden(angle), &cfg, gb_rows)?;
            println!(
                "{} {}: ({:.1} s)",
                angle.symbol(),
                kind.name(),
                t0.elapsed().as_secs_f64()
            );
            print_metrics("float", &m);
        }
    }
    Ok(())
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match &cli.cmd {
        Cmd::Train {
            args,
            out,
            weights_out,
            vectors_out,
            no_export,
        } => cmd_train(args, out, weights_out, vectors_out, *no_export),
        Cmd::Eval { data, json } => cmd_eval(data, *json),
        Cmd::Baselines { args, gb_rows } => cmd_baselines(args, *gb_rows),
    }
}
