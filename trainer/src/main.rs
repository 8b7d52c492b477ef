use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use estimator_core::Suite;
use hil_sim::dataset::machine;
use std::path::{Path, PathBuf};
use trainer::data::{Dataset, PAPER_TRAIN_ROWS, Role};
use trainer::export::{plot_curves, plot_series, provenance, write_model};
use trainer::features::{FeatureSet, SHIPPED as SHIPPED_FEATURES, parse_suite};
use trainer::metrics::FlightMetrics;
use trainer::model::{Loss, TrainConfig};
use trainer::pipeline::{Size, eval_shipped, prepare_angle, train_angle, train_prepared};
use trainer::prep::Angle;

fn parse_loss(s: &str) -> std::result::Result<Loss, String> {
    Loss::parse(s).ok_or_else(|| format!("`{s}`: the loss is mse or l1"))
}

/// A learning rate: finite and > 0.
fn learning_rate(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        Ok(_) => Err(format!(
            "`{s}`: the learning rate must be a positive number, e.g. 1e-3"
        )),
        Err(_) => Err(format!("`{s}` is not a number")),
    }
}

/// The share of training flights held out for validation: strictly between 0 and 1.
fn fraction(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x < 1.0 => Ok(x),
        Ok(_) => Err(format!(
            "`{s}`: a fraction strictly between 0 and 1, e.g. 0.15"
        )),
        Err(_) => Err(format!("`{s}` is not a number")),
    }
}

/// `--epochs` of the benchmarks: at least 2, as the first epoch is warm-up and is not averaged.
fn bench_epochs(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n >= 2 => Ok(n),
        Ok(_) => Err("must be at least 2 (the first epoch is warm-up and is not averaged)".into()),
        Err(_) => Err(format!("`{s}` is not a whole number")),
    }
}

/// Seeds given as one comma-separated value (`--seeds 1,2,3`).
#[derive(Clone, Debug)]
struct Seeds(Vec<u64>);

/// A comma-separated seed list, e.g. `1,2,3` (at least one seed, none repeated).
fn seed_list(s: &str) -> std::result::Result<Seeds, String> {
    let seeds = s
        .split(',')
        .map(|x| x.trim().parse::<u64>())
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|_| format!("`{s}`: comma-separated whole numbers, e.g. 1,2,3"))?;
    let mut sorted = seeds.clone();
    sorted.sort_unstable();
    sorted.dedup();
    if sorted.len() != seeds.len() {
        return Err(format!("`{s}`: a seed is repeated"));
    }
    Ok(Seeds(seeds))
}

#[derive(Parser)]
#[command(
    version,
    about = "Train, quantize, export and evaluate the synthetic air data estimator"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
    /// The aircraft (its description, `aircraft/NAME.toml`). A build carries one aircraft, the
    /// default; another name is refused with how to build for it.
    #[arg(long, global = true, value_name = "NAME", value_parser = hil_sim::cli_values::this_builds_aircraft)]
    // Checked by its value parser: a parsed value is this build's aircraft.
    #[allow(dead_code)]
    aircraft: Option<String>,
}

/// `--replicas`, shared by `train`, `bench-epoch` and `bench-train`.
#[derive(clap::Args, Clone, Copy)]
struct Replicas {
    /// Replicas each training batch is split over (1 to 8; default: 2 for a model with a layer of
    /// 256 or more outputs, else 1, `model::auto_replicas`). Part of what a seed reproduces.
    #[arg(long = "replicas", value_name = "REPLICAS", value_parser = clap::value_parser!(u64).range(1..=8))]
    n: Option<u64>,
}

impl Replicas {
    /// `TrainConfig::replicas`.
    fn get(self) -> Option<usize> {
        self.n.map(|r| r as usize)
    }
}

#[derive(clap::Args, Clone)]
struct TrainArgs {
    /// Dataset directory (manifest.json + CSVs from `hil-sim generate`).
    #[arg(long, value_name = "DIR")]
    data: PathBuf,
    /// More training flights: every training flight of this dataset (its test flights are left
    /// out) trains with `--data`'s, while validation and test stay `--data`'s own flights, so runs
    /// with and without it are selected and scored on the same flights. Repeatable. A flight held
    /// already (the same name, seed and profile) is refused; another flight under a name held
    /// (two campaigns name their flights alike) trains as NAME~SEED.
    #[arg(long, value_name = "DIR")]
    extra_data: Vec<PathBuf>,
    /// Accept --extra-data flights of other aircraft (manifest `aircraft`) on purpose: training
    /// on randomised airframes (scripts/airframe-randomise). Without it they are refused.
    #[arg(long)]
    mixed_aircraft: bool,
    /// Score on this dataset's test flights instead of --data's (its training flights are not
    /// used), named `DATASET/FLIGHT`: the airframe really flown, when the model trains on another
    /// aircraft's flights, e.g. a calibrated aircraft's (scripts/calibrate) scored on the variant
    /// it was calibrated for. Repeatable: the test flights of every one.
    #[arg(long, value_name = "DIR")]
    test_data: Vec<PathBuf>,
    /// Add a gyro-bias twin of every training flight, drawn from this seed: up to four windows
    /// of the flight, each with one gyro (p, q or r) biased by 0.005-0.3 rad/s (log-uniform,
    /// either sign) for 3-15 s, its truth the flight's
    /// (trainer::data::Dataset::add_gyro_bias_twins). The networks learn not to read a gyro's
    /// step as a change of the air data. Validation and test flights stay as flown.
    #[arg(long, value_name = "SEED")]
    gyro_bias_twins: Option<u64>,
    /// Which networks train on the gyro-bias twins: both, alpha or beta (the other then trains on
    /// exactly the rows it would without them). Default: both.
    #[arg(long, value_enum, requires = "gyro_bias_twins", default_value_t = trainer::data::TwinAngles::Both)]
    gyro_bias_twins_for: trainer::data::TwinAngles,
    /// Seed of the weight initialisation, the validation split's draw and the batch order: the
    /// same seed, data and flags give the same weights, bit for bit.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Network configuration: small (CI), medium, large (the largest that fits the target
    /// budget), medium-wide-beta (α as medium, β as large), medium-wider-beta (α as medium, β
    /// 128-64-32), or paper. Default: the shipped sizes of the build's aircraft (its description's
    /// `estimator.config`).
    #[arg(long, default_value = estimator_core::aircraft::AIRCRAFT.estimator.config)]
    config: String,
    /// Epochs (default: 40 small, 30 every other configuration).
    #[arg(long, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
    epochs: Option<usize>,
    /// Mini-batch size, rows.
    #[arg(long, default_value_t = 256, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
    batch: usize,
    /// Adam learning rate.
    #[arg(long, default_value_t = 1e-3, value_parser = learning_rate, allow_hyphen_values = true)]
    lr: f64,
    /// Training loss of both heads: mse (the paper's) or l1 (mean absolute error, the metric the
    /// accuracy tables report; the shipped configuration's).
    #[arg(long, default_value = "l1", value_parser = parse_loss)]
    loss: Loss,
    #[command(flatten)]
    replicas: Replicas,
    /// Input features: table1, physics (Table 1 + specific force/ρV² + Mach proxy), dynamics
    /// (physics + short-term deltas of the sensed channels, see trainer/src/features.rs),
    /// egi-dynamics (dynamics + the EGI attitude, climb rate and fuel, the ground velocity in body
    /// axes and the kinematic α/β; needs --suite egi), egi-hybrid (egi-dynamics + the model-based
    /// air-data filter's α, β, their 1σ, air speed and lift scale; --suite egi), egi-hybrid-fast
    /// (egi-dynamics + the filter's α, β and their 1σ, which recover within a second of an
    /// outage), egi-hybrid-fast-d2 (egi-hybrid-fast + the β dynamics channels' 2-frame deltas),
    /// egi120-beta (egi-hybrid-fast-d2 + the 120 Hz sub-samples of Ay, rudder, aileron and r for
    /// β; --suite egi120), egi120 (egi120-beta + those of Az, q and elevator for α),
    /// egi120-side-scale (egi120 + the filter's side-force scale for β), egi120-gyro-p
    /// (egi120 + the roll gyro's 120 Hz sub-samples for β), egi120-gyro-p-beta-alpha
    /// (egi120-gyro-p with β also reading every input of α: through the lift, the dynamic
    /// pressure), egi120-gyro-p-beta-alpha-own (the same without the inputs that read a sensor β
    /// did not read, the flap's excepted), egi120-gyro-p-no-axial (egi120-gyro-p
    /// without Ax, throttle, Fx/ρV² and their changes for α), egi-hybrid-scales
    /// (egi-hybrid-fast-d2 + the filter's lift and side-force scales),
    /// egi-hybrid-turb (egi-hybrid + the filter's turbulence index), or
    /// "alpha=a,b,...;beta=c,d,..." with feature names (trainer/src/features.rs lists them).
    /// Default: the shipped set of the build's aircraft (its description's `estimator.features`).
    #[arg(long)]
    features: Option<String>,
    /// Feature names to take out of `--features` for both angles (comma-separated, e.g.
    /// `filter_airspeed_mps,filter_lift_scale`): an ablation without spelling out the whole list.
    #[arg(long, default_value = "")]
    without: String,
    /// Sensor suite the models may read: table1 (the paper's inputs), egi (Table 1 + the
    /// embedded GPS/INS attitude and velocity and the fuel quantity; needs a dataset of format 4)
    /// or egi120 (egi + the IMU's and the surfaces' 120 Hz sub-samples, the shipped suite; needs a
    /// dataset of format 5). A feature of a suite the run does not have is refused with the suite
    /// it needs.
    #[arg(long, default_value = "egi120")]
    suite: String,
    /// Fraction of training flights held out (by flight) for validation, strictly between 0 and 1.
    #[arg(long, default_value_t = 0.15, value_parser = fraction, allow_hyphen_values = true)]
    val_fraction: f64,
}

/// `trainer report`'s arguments.
#[derive(clap::Args)]
struct ReportArgs {
    #[command(flatten)]
    args: TrainArgs,
    /// Seeds of the neural models, comma-separated.
    #[arg(long, default_value = "1,2", value_parser = seed_list)]
    seeds: Seeds,
    /// Feature set of the ablation against --features ("none": skip).
    #[arg(long, default_value = "physics")]
    ablation: String,
    /// Training rows (evenly subsampled) for gradient boosting.
    #[arg(long, default_value_t = 40_000, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
    gb_rows: usize,
    /// Output directory of training.md and the PNGs (`--out docs/results` refreshes the committed
    /// report).
    #[arg(long, value_name = "DIR", default_value = "out/report")]
    out: PathBuf,
    /// Print exactly one JSON object (the Table-2 numbers) on stdout.
    #[arg(long)]
    json: bool,
    /// Also the rows of what ships: the shipped configuration (the hybrid: the aircraft's
    /// `estimator.features` on the `egi120` suite, networks of its `estimator.config` trained with
    /// `--loss l1`, the report's seeds and epochs) and the model-based filter alone. Needs a dataset that carries the `egi120` suite (format 5).
    #[arg(long)]
    shipped_rows: bool,
    /// An out-of-distribution dataset (`hil-sim generate --preset ood`): every row also answers
    /// on its flights, and the report gets the degradation of each row per case against the
    /// in-distribution twins.
    #[arg(long)]
    ood: Option<PathBuf>,
}

/// The grid and training settings of `trainer sweep` (the same for every call of one sweep).
#[derive(clap::Args, Clone)]
struct SweepGrid {
    /// Dataset directory (manifest.json + CSVs from `hil-sim generate`).
    #[arg(long, value_name = "DIR")]
    data: PathBuf,
    /// Output directory of the job results and sweep.md (shared by every job).
    #[arg(long, value_name = "DIR", default_value = "out/sweep")]
    out: PathBuf,
    /// Network configurations (repeat the flag for several), as `trainer train --config`.
    #[arg(long = "config", default_value = "small")]
    sizes: Vec<String>,
    /// Feature sets (repeat the flag for several), as `trainer train --features`.
    #[arg(long = "features", default_value = "table1")]
    features: Vec<String>,
    /// Sensor suites (repeat the flag for several): table1, egi, egi120.
    #[arg(long = "suite", default_value = "table1")]
    suites: Vec<String>,
    /// Seeds, comma-separated.
    #[arg(long, default_value = "1", value_parser = seed_list)]
    seeds: Seeds,
    /// Epochs (default: the configuration's).
    #[arg(long, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
    epochs: Option<usize>,
    /// Mini-batch size, rows.
    #[arg(long, default_value_t = 256, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
    batch: usize,
    /// Adam learning rate.
    #[arg(long, default_value_t = 1e-3, value_parser = learning_rate, allow_hyphen_values = true)]
    lr: f64,
    /// Training loss of both heads, as `trainer train --loss`.
    #[arg(long, default_value = "mse", value_parser = parse_loss)]
    loss: Loss,
    /// Fraction of training flights held out for validation, strictly between 0 and 1.
    #[arg(long, default_value_t = 0.15, value_parser = fraction, allow_hyphen_values = true)]
    val_fraction: f64,
}

/// Exactly one of these.
#[derive(clap::Args, Clone)]
#[group(required = true, multiple = false)]
struct SweepAction {
    /// Print the jobs (first line: `jobs: N`).
    #[arg(long)]
    list: bool,
    /// Run job K (0 ≤ K < N; a Slurm array task passes $SLURM_ARRAY_TASK_ID).
    #[arg(long)]
    job: Option<usize>,
    /// Gather the jobs' results into OUT/sweep.md.
    #[arg(long)]
    merge: bool,
}

#[derive(Subcommand)]
enum Cmd {
    /// Train both cascades and quantize them; writes plots, summary.json and model.json (the
    /// int8 model, for `trainer eval --model` and `trainer export`) into --out. With --export it
    /// also writes the weights the estimator compiles in and their test vectors into the source
    /// tree.
    Train {
        #[command(flatten)]
        args: TrainArgs,
        /// Output directory of the plots, summary.json and model.json.
        #[arg(long, value_name = "DIR", default_value = "out/train")]
        out: PathBuf,
        /// Also export into the source tree (--weights-out, --vectors-out): the next build of
        /// estimator-core, hil-sim and the firmware carries this model.
        #[arg(long)]
        export: bool,
        /// Where --export writes the generated weights [default: the build's aircraft's
        /// estimator-core/src/model/NAME/weights.rs].
        #[arg(long, value_name = "FILE")]
        weights_out: Option<PathBuf>,
        /// Where --export writes the bit-exactness test vectors [default:
        /// estimator-core/tests/vectors/NAME.txt].
        #[arg(long, value_name = "FILE")]
        vectors_out: Option<PathBuf>,
    },
    /// Export a model `trainer train` saved (its `model.json`) into the source tree, as
    /// `train --export` would have: the same weights.rs (its provenance the training's) and test
    /// vectors (frames of --data's own test flights, as a training without --test-data takes
    /// them), without training again. Choose a model on its `trainer eval --model` figures, then
    /// ship it with this.
    Export {
        /// The directory `trainer train --out` wrote (model.json).
        #[arg(long, value_name = "DIR")]
        model: PathBuf,
        /// The dataset the model was trained with (`--data` of its training; refused if its manifest
        /// is not the one the model's provenance names): the test vectors are frames of its test
        /// flights.
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
        /// Where the weights go [default: the build's aircraft's
        /// estimator-core/src/model/NAME/weights.rs].
        #[arg(long, value_name = "FILE")]
        weights_out: Option<PathBuf>,
        /// Where the test vectors go [default: estimator-core/tests/vectors/NAME.txt].
        #[arg(long, value_name = "FILE")]
        vectors_out: Option<PathBuf>,
    },
    /// Remake the expected outputs of the committed test vectors (the same frames, the same
    /// header) for the compiled-in networks, on this build's features: after a change of the
    /// air-data filter or of the feature code, from which the vectors' expected outputs come. The
    /// networks are read back from their weights.rs (refused unless they generate the same file
    /// byte for byte), so no model.json is needed; the weights do not change.
    Revector {
        /// The weights.rs `trainer train --export` wrote [default: the build's aircraft's
        /// estimator-core/src/model/NAME/weights.rs].
        #[arg(long, value_name = "FILE")]
        weights: Option<PathBuf>,
        /// The test vectors to remake, in place [default: estimator-core/tests/vectors/NAME.txt].
        #[arg(long, value_name = "FILE")]
        vectors: Option<PathBuf>,
    },
    /// One model of the α network of one saved model and the β network of another (both
    /// `trainer train --out` directories, of one sensor suite and one --data): writes --out's
    /// model.json, for `trainer eval --model` and `trainer export`. The two networks are trained
    /// apart, so each can be chosen from its own training.
    Combine {
        /// The model whose α network is taken (its model.json).
        #[arg(long, value_name = "DIR")]
        alpha: PathBuf,
        /// The model whose β network is taken (its model.json).
        #[arg(long, value_name = "DIR")]
        beta: PathBuf,
        /// Where model.json goes (created; an existing model.json there is refused).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
    },
    /// Table 2 baselines (linear regression, gradient boosting, plain MLP) on the test flights.
    Baselines {
        #[command(flatten)]
        args: TrainArgs,
        /// Training rows (evenly subsampled) for gradient boosting.
        #[arg(long, default_value_t = 40_000, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        gb_rows: usize,
    },
    /// Table 2: every model family for α and β on the same test flights (float and int8), seed
    /// spread, feature ablation; writes training.md + learning-curve and time-series PNGs.
    Report(Box<ReportArgs>),
    /// Spearman rank correlations of every candidate feature with the air-data targets and among
    /// themselves (CSV + markdown + heatmap), and sampled Shapley values of the compiled-in α and β
    /// models' integer path (mean |SHAP| bar charts); writes features.md.
    Features {
        /// Dataset directory (manifest.json + CSVs from `hil-sim generate`).
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
        /// Output directory of features.md, the CSV and the PNGs (`--out docs/results` refreshes
        /// the committed page).
        #[arg(long, value_name = "DIR", default_value = "out/features")]
        out: PathBuf,
        /// Training rows (evenly subsampled) used for the correlations.
        #[arg(long, default_value_t = 60_000, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        rows: usize,
        /// SHAP sampling seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// SHAP: test rows explained (evenly spread over the test flights).
        #[arg(long, default_value_t = 200, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        explain: usize,
        /// SHAP: background rows (evenly spread over the training flights).
        #[arg(long, default_value_t = 32, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        background: usize,
        /// SHAP: feature permutations per explained row.
        #[arg(long, default_value_t = 8, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        permutations: usize,
    },
    /// Times training epochs of the paper-size α cascade (512-256-128-64-32 per part).
    BenchEpoch {
        /// Dataset directory (manifest.json + CSVs from `hil-sim generate`).
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
        /// Epochs timed (at least 2: the first is warm-up, reported apart).
        #[arg(long, default_value_t = 3, value_parser = bench_epochs, allow_hyphen_values = true)]
        epochs: usize,
        /// Mini-batch size, rows.
        #[arg(long, default_value_t = 256, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        batch: usize,
        /// Output directory of bench_epoch.json (`trainer report --out DIR` includes
        /// DIR/bench_epoch.json in its page).
        #[arg(long, value_name = "DIR", default_value = "out/bench-epoch")]
        out: PathBuf,
        #[command(flatten)]
        replicas: Replicas,
    },
    /// burn against PyTorch on the same cascade, data, initial weights, batches and threads
    /// (run it through scripts/bench-train, which makes the PyTorch venv).
    BenchTrain {
        /// Dataset directory (manifest.json + CSVs from `hil-sim generate`).
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
        /// Epochs per run (at least 2: the first is warm-up and is not averaged).
        #[arg(long, default_value_t = 5, value_parser = bench_epochs, allow_hyphen_values = true)]
        epochs: usize,
        /// Mini-batch size, rows.
        #[arg(long, default_value_t = 256, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        batch: usize,
        /// Threads for both frameworks (burn: rayon's global pool; PyTorch: set_num_threads).
        #[arg(long, default_value_t = 2, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        threads: usize,
        /// Seeds, comma-separated (at most 20), each a full side-by-side run; the page and the JSON
        /// compare the means over seeds (one seed's validation loss is mostly epoch-to-epoch noise).
        #[arg(long, default_value = "1,2,3", value_parser = seed_list)]
        seeds: Seeds,
        /// Cases to run (paper-alpha, shipped-alpha); default all.
        #[arg(long, value_delimiter = ',')]
        case: Vec<String>,
        /// The benchmark venv's Python (with torch).
        #[arg(long, default_value = ".venv-bench/bin/python")]
        python: PathBuf,
        /// The PyTorch side of the benchmark.
        #[arg(long, default_value = "scripts/bench/torch_train.py")]
        torch_script: PathBuf,
        /// Output directory of training-speed.md and training-speed.json (`--out docs/results`
        /// refreshes the committed page); the exchanged matrices, weights and batch orders go to
        /// DIR/exchange.
        #[arg(long, value_name = "DIR", default_value = "out/bench-train")]
        out: PathBuf,
        /// Print exactly one JSON object on stdout.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        replicas: Replicas,
    },
    /// Score the model-based air-data filter alone (EGI suite) on a dataset's
    /// flights, frame by frame as the firmware runs it.
    EvalFilter {
        /// Dataset directory (manifest.json + CSVs from `hil-sim generate`), egi suite.
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
        /// Which flights: `test` (the manifest's test flights), `train` or `val` (for tuning: never
        /// tune on `test`).
        #[arg(long, default_value = "test")]
        split: String,
        /// Override filter constants for a tuning run, e.g. `gust_sigma=3,accel_sigma_z=0.8`
        /// (keys: gust_sigma, gust_tau_s, accel_sigma_y, accel_sigma_z, accel_delay_s, gate, max_sigma_rad,
        /// mean_wind_psd_h, mean_wind_psd_d, mean_wind_sigma0_d, lift_scale_psd, lift_scale_sigma0, side_scale_psd, side_scale_sigma0, te_lift_sigma0 and te_lift_psd (a build with the trailing-edge lift state only), subsamples (0 off, 1 latest, 2 period mean), gear_norm, r_adapt_tau_s, r_adapt_lo_y,
        /// r_adapt_hi_y, r_adapt_lo_z, r_adapt_hi_z).
        #[arg(long, default_value = "")]
        tune: String,
        /// Print exactly one JSON object.
        #[arg(long)]
        json: bool,
        /// Also write, frame by frame, the normal specific force the IMU measures beside the one
        /// the filter's force model gives at the flight's true air-data point and at the filter's
        /// estimate (CSV; scripts/analysis/force-residual reads it). Needs the dataset's truth.
        #[arg(long, value_name = "FILE")]
        frames: Option<PathBuf>,
    },
    /// Draw grouped horizontal bars from a JSON description, for the scripts' reports
    /// (scripts/calibration-accuracy): `{"series": [..], "panels": [{"title": .., "xlabel": ..,
    /// "rows": [[label, [value per series]], ..]}, ..]}`.
    Bars {
        /// The JSON description.
        #[arg(long, value_name = "FILE")]
        spec: PathBuf,
        /// The PNG to write.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
    },
    /// Draw line-chart panels side by side from a JSON description, for the analysis scripts
    /// (scripts/analysis/force-residual): `{"panels": [{"title": .., "xlabel": .., "ylabel": ..,
    /// "series": [{"name": .., "points": [[x, y], ..]}, ..]}, ..]}`; one legend below them.
    Lines {
        /// The JSON description.
        #[arg(long, value_name = "FILE")]
        spec: PathBuf,
        /// The PNG to write.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
    },
    /// Out-of-distribution table: the shipped estimator and the filter alone on the `ood` preset's
    /// flights (`hil-sim generate --preset ood`), each against its in-distribution twin, with the
    /// flights where flags stayed clear through large errors called out; writes ood.md, ood.json
    /// and ood.png.
    Ood {
        /// The `ood` dataset (`hil-sim generate --preset ood`).
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
        /// Output directory of ood.md, ood.json and ood.png (`--out docs/results` refreshes the
        /// committed page).
        #[arg(long, value_name = "DIR", default_value = "out/ood")]
        out: PathBuf,
        /// Print exactly one JSON object on stdout (the files are written as well).
        #[arg(long)]
        json: bool,
    },
    /// Training sweep: a grid of sizes × feature sets × suites × seeds as numbered independent jobs.
    /// `--list` prints them, `--job K` trains job K (both cascades) and leaves OUT/job-K.json,
    /// `--merge` gathers them into OUT/sweep.md with the seed spread, naming every failed or missing
    /// job (and exits non-zero if there is one). Every call takes the same grid arguments.
    Sweep {
        #[command(flatten)]
        grid: SweepGrid,
        #[command(flatten)]
        action: SweepAction,
    },
    /// Flight-test calibration: from a `flight-test` dataset's production sensors, nose boom and
    /// engine channels (never its truth columns), check the boom against the inertial data and
    /// identify the lift scale, the flap-lift scale, a lift offset, the side force's two scales
    /// (its sideslip terms', and its surface and rate terms', from the rolling frames; over the
    /// moment card when given, as the roll and yaw), the drag
    /// and the engine deck's thrust scales (the thrust carried when 2σ or more from 1) and the
    /// roll and yaw moment scales (the gyros differentiated; only over the model card, or over the
    /// moment card flown on a first calibrated aircraft; carried within 0.75–1.33, drawn toward 1
    /// by a wind-tunnel prior of 1σ 0.10) of the aircraft against the model the estimator knows (equation error); writes
    /// calibration.json, calibration.md and aircraft.toml (a scripts/airframe-variant spec of the
    /// calibrated aircraft) into --out. scripts/calibrate runs it and builds the rest.
    Calibrate {
        /// The flight-test dataset (`hil-sim generate --preset flight-test`).
        #[arg(long, value_name = "DIR")]
        flight_test: PathBuf,
        /// The same test card flown in simulation on the model the estimator knows (`hil-sim
        /// generate --preset flight-test --seed N`, N not the flight test's seed): the
        /// identification's own bias on the model's aircraft, divided out of the scales. Its
        /// sensors and boom only. Repeat it for the card flown on further sensor seeds, one
        /// directory each (scripts/calibrate flies 8): the scales divided out are their mean, and
        /// their spread joins the 1σ.
        #[arg(long, value_name = "DIR")]
        model_flight_test: Vec<PathBuf>,
        /// The same test card flown on the calibrated aircraft of a first `trainer calibrate`
        /// with the model cards alone (its aircraft.toml made an aircraft by
        /// `scripts/airframe-variant`), on sensor seeds other than the flight test's. The roll and
        /// yaw scales and the side force's two scales are then the flight test's over these cards'
        /// bias (their fit over the scale that aircraft carries, pooled as the model cards): those
        /// fits' bias depends on where the aircraft flies. Needs --model-flight-test and --first-calibration;
        /// scripts/calibrate flies 8.
        #[arg(long, value_name = "DIR", requires = "first_calibration")]
        moment_flight_test: Vec<PathBuf>,
        /// The first calibration's calibration.json, whose aircraft the moment cards flew: the
        /// roll, yaw and side-force scales that aircraft carries.
        #[arg(long, value_name = "FILE", requires = "moment_flight_test")]
        first_calibration: Option<PathBuf>,
        /// Output directory.
        #[arg(long, value_name = "DIR", default_value = "out/calibration")]
        out: PathBuf,
        /// Print exactly one JSON object on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Fine-tune a trained model's networks on a flight test: their targets the nose boom's air
    /// data (its lag undone, corrected by the data-compatibility check), never the simulator's
    /// truth. Every 5th block of 30 s is held out; the epoch of the lowest held-out loss is kept
    /// where it beats the model as it was. Writes model.json (float and int8, for `trainer eval
    /// --model` and `trainer export`) and summary.json into --out.
    Finetune {
        /// The directory `trainer train --out` wrote (its model.json, with the float weights).
        #[arg(long, value_name = "DIR")]
        model: PathBuf,
        /// The flight-test dataset (`hil-sim generate --preset flight-test`).
        #[arg(long, value_name = "DIR")]
        flight_test: PathBuf,
        /// Output directory (refused if it holds a model.json already).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Epochs.
        #[arg(long, default_value_t = 10, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        epochs: usize,
        /// Adam learning rate (cosine-decayed over the epochs).
        #[arg(long, default_value_t = 1e-4, value_parser = learning_rate, allow_hyphen_values = true)]
        lr: f64,
        /// Mini-batch size, rows.
        #[arg(long, default_value_t = 256, value_parser = hil_sim::cli_values::at_least_one, allow_hyphen_values = true)]
        batch: usize,
        /// Seed of the batch order.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Loss of both heads, as `trainer train --loss`.
        #[arg(long, default_value = "l1", value_parser = parse_loss)]
        loss: Loss,
        /// A simulated dataset (the model's `--data`, e.g. out/data/large) whose training flights'
        /// rows are trained on beside the flight test's, as many again, so that what the card
        /// does not fly (turbulence, other speeds) is not forgotten.
        #[arg(long, value_name = "DIR")]
        replay: Option<PathBuf>,
        /// What trains: `all` (every parameter) or `output` (part 2's output layer alone).
        #[arg(long, default_value = "all", value_parser = parse_tune)]
        tune: trainer::finetune::Tune,
        /// Print exactly one JSON object (summary.json) on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Fit the weights of the estimate's 1σ (estimator-core's `uncertainty`) for the compiled-in
    /// estimator, on flights none of its networks trained on: writes the generated sigma.rs the
    /// estimator compiles in, and prints the coverage on those flights.
    FitSigma {
        /// Datasets whose every flight is stepped (repeatable; e.g. randomised airframes from
        /// scripts/airframe-randomise and JSBSim's own F-16). None of their flights may have
        /// trained the compiled-in networks.
        #[arg(long, value_name = "DIR", required = true)]
        data: Vec<PathBuf>,
        /// Fit on every N-th frame (the errors of neighbouring frames are nearly the same); the
        /// coverage is reported on every frame.
        #[arg(long, default_value_t = 5)]
        every: usize,
        /// The generated file to write [default: the build's aircraft's
        /// estimator-core/src/model/NAME/sigma.rs].
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
        /// Also write every row (dataset, flight, the frame's row in the flight's CSV, angle, the
        /// terms, the 1σ of the weights compiled in, the error; millidegrees) as CSV, to study
        /// which terms follow the error (scripts/analysis/sigma-spread).
        #[arg(long, value_name = "CSV")]
        rows: Option<PathBuf>,
        /// Print exactly one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Evaluate the compiled-in estimator (int8, with its flags and fallbacks, as the firmware runs
    /// it) on a dataset's flights; or, with --model, a model `trainer train` wrote, without
    /// exporting it.
    Eval {
        /// Dataset directory (manifest.json + CSVs from `hil-sim generate` or `hil-sim fly`).
        #[arg(long, value_name = "DIR")]
        data: PathBuf,
        /// A `trainer train --out` directory: evaluate its int8 networks (model.json; the
        /// networks alone, without the compiled-in estimator's flags and fallbacks). Given more
        /// than once, the models' mean (an ensemble: each frame's angle is the mean of theirs).
        #[arg(long, value_name = "DIR")]
        model: Vec<PathBuf>,
        /// Which flights: `test` (the manifest's test flights), `train` or `val` (to see how the
        /// shipped estimator behaves in distribution, e.g. how often its flags fire).
        #[arg(long, default_value = "test")]
        split: String,
        /// Sensor suite of the frames the model is stepped with (table1, egi or egi120): as a
        /// sender of that suite delivers them. A model that reads a channel the suite lacks is
        /// refused. Default: the suite the compiled-in model reads; with --model, the first
        /// model's (every other model must read within it).
        #[arg(long)]
        suite: Option<String>,
        /// Frames for which `UNCERTAIN` stays raised after a 1σ was last above its limit (0–255),
        /// to measure that choice; default: the firmware's, `UNCERTAIN_HOLD_FRAMES`. Not with
        /// --model (the networks alone carry no flags).
        #[arg(long, value_name = "FRAMES")]
        uncertain_hold: Option<u8>,
        /// Print exactly one JSON object.
        #[arg(long)]
        json: bool,
    },
}

impl TrainArgs {
    fn size(&self) -> Result<Size> {
        Size::parse(&self.config).with_context(|| format!("--config must be {}", Size::choices()))
    }

    fn epochs(&self, size: Size) -> usize {
        self.epochs.unwrap_or(size.default_epochs())
    }

    fn train_config(&self, size: Size, label: String, progress: bool) -> TrainConfig {
        TrainConfig {
            epochs: self.epochs(size),
            batch: self.batch,
            lr: self.lr,
            seed: self.seed,
            label,
            progress,
            loss: self.loss,
            replicas: self.replicas.get(),
            bars: None,
        }
    }

    /// The sensor suite and the feature set, checked against each other.
    fn suite_features(&self) -> Result<(Suite, FeatureSet)> {
        let suite = parse_suite(&self.suite)?;
        let fs = FeatureSet::parse(self.features.as_deref().unwrap_or(SHIPPED_FEATURES))?
            .without(&self.without)?;
        fs.check_suite(suite)?;
        Ok((suite, fs))
    }

    /// The dataset, split by flight, with at least one validation flight, carrying `suite`.
    fn dataset(&self, suite: Suite) -> Result<Dataset> {
        let mut ds = load(&self.data, self.val_fraction)?;
        for dir in &self.extra_data {
            ds.add_training(dir, self.mixed_aircraft)
                .with_context(|| format!("adding the training flights of {}", dir.display()))?;
        }
        if let Some(seed) = self.gyro_bias_twins {
            ds.add_gyro_bias_twins(seed, self.gyro_bias_twins_for);
        }
        for dir in &self.test_data {
            ds.test_on(dir)
                .with_context(|| format!("taking the test flights of {}", dir.display()))?;
        }
        ds.require(suite)?;
        if ds.rows(trainer::data::Role::Val) == 0 {
            bail!("no validation flight: the dataset needs at least two training flights");
        }
        Ok(ds)
    }
}

fn load(data: &Path, val_fraction: f64) -> Result<Dataset> {
    Dataset::load(data, val_fraction).with_context(|| format!("loading dataset {}", data.display()))
}

/// The first of `path` and its ancestors that exists, when it is not a directory: the file that
/// stops a directory from being created at `path`.
fn blocking_file(path: &Path) -> Option<&Path> {
    path.ancestors()
        .filter(|a| !a.as_os_str().is_empty())
        .find(|a| a.exists())
        .filter(|a| !a.is_dir())
}

/// An output directory (`flag DIR`), checked before any work: a directory, or one that can be
/// created (no file stands at it or at a parent).
fn check_out_dir(flag: &str, dir: &Path) -> Result<()> {
    match blocking_file(dir) {
        Some(f) if f == dir => bail!(
            "{flag} {} is a file, not a directory: give a directory",
            dir.display()
        ),
        Some(f) => bail!(
            "{flag} {}: {} is a file, so no directory can be made there",
            dir.display(),
            f.display()
        ),
        None => Ok(()),
    }
}

/// An output file (`flag FILE`), checked before any work: not a directory, and in a directory that
/// exists (or, when the command makes it, `makes_dir`, one that can be created).
fn check_out_file(flag: &str, file: &Path, makes_dir: bool) -> Result<()> {
    if file.is_dir() {
        bail!(
            "{flag} {} is a directory: give the file to write",
            file.display()
        );
    }
    let Some(dir) = file.parent().filter(|p| !p.as_os_str().is_empty()) else {
        return Ok(());
    };
    if makes_dir {
        if let Some(f) = blocking_file(dir) {
            bail!(
                "{flag} {}: {} is a file, so its directory cannot be made",
                file.display(),
                f.display()
            );
        }
    } else if !dir.is_dir() {
        bail!(
            "{flag} {}: the directory {} does not exist; create it first",
            file.display(),
            dir.display()
        );
    }
    Ok(())
}

/// Where a command writes, checked before it reads or computes anything: an output that cannot be
/// written is refused up front, not after the work.
fn check_outputs(cmd: &Cmd) -> Result<()> {
    let dir = match cmd {
        Cmd::Train { out, .. }
        | Cmd::Combine { out, .. }
        | Cmd::Ood { out, .. }
        | Cmd::Calibrate { out, .. }
        | Cmd::Finetune { out, .. }
        | Cmd::Features { out, .. }
        | Cmd::BenchEpoch { out, .. }
        | Cmd::BenchTrain { out, .. } => Some(out),
        Cmd::Report(r) => Some(&r.out),
        Cmd::Sweep { grid, .. } => Some(&grid.out),
        _ => None,
    };
    if let Some(dir) = dir {
        check_out_dir("--out", dir)?;
    }
    match cmd {
        Cmd::Train {
            export: true,
            weights_out,
            vectors_out,
            ..
        }
        | Cmd::Export {
            weights_out,
            vectors_out,
            ..
        } => {
            let (w, v) = export_paths(weights_out, vectors_out);
            check_out_file("--weights-out", &w, true)?;
            check_out_file("--vectors-out", &v, true)?;
        }
        Cmd::FitSigma { out, rows, .. } => {
            check_out_file("--out", &committed(out, "src/model/{}/sigma.rs"), false)?;
            if let Some(rows) = rows {
                check_out_file("--rows", rows, false)?;
            }
        }
        Cmd::EvalFilter {
            frames: Some(f), ..
        } => check_out_file("--frames", f, false)?,
        _ => {}
    }
    Ok(())
}

/// This process's command line, for provenance and reports.
fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

fn print_metrics(label: &str, m: &FlightMetrics) {
    let rows = m.per_flight.iter().map(|(n, x)| (n.as_str(), x));
    for (name, x) in rows.chain(std::iter::once(("OVERALL", &m.overall))) {
        println!(
            "  {label:<6} {name:<24} MAE {}  RMSE {}  p95 {}  max {}  (n={})",
            x.cell(x.mae, 7),
            x.cell(x.rmse, 7),
            x.cell(x.p95, 7),
            x.cell(x.max, 7),
            x.n
        );
    }
}

fn cmd_train(
    args: &TrainArgs,
    out: &PathBuf,
    weights_out: &Path,
    vectors_out: &Path,
    export: bool,
) -> Result<()> {
    let size = args.size()?;
    let (suite, fs) = args.suite_features()?;
    let mut ds = args.dataset(suite)?;
    // Training reads the training flights' features, never their frames.
    ds.drop_training_frames();
    eprintln!(
        "dataset {} (sensor suite {}): train {} rows, val {} rows, test {} rows",
        args.data.display(),
        suite.name(),
        ds.rows(trainer::data::Role::Train),
        ds.rows(trainer::data::Role::Val),
        ds.rows(trainer::data::Role::Test)
    );
    let epochs = args.epochs(size);
    // α and β train side by side: each is deterministic on any number of threads, so this
    // changes no bit, and the shipped networks' small layers leave a core idle each on its own.
    let bars = indicatif::MultiProgress::new();
    let cfg = |a: Angle| TrainConfig {
        bars: Some(bars.clone()),
        ..args.train_config(size, a.name().into(), true)
    };
    // Both angles' matrices first, then the training rows go: a training row's features are
    // larger than its inputs to both networks together.
    let twins = ds.gyro_bias_twins.map(|t| t.angles).unwrap_or_default();
    let (pa, pb) = (
        prepare_angle(&ds, Angle::Alpha, &fs.alpha, size, twins.alpha()),
        prepare_angle(&ds, Angle::Beta, &fs.beta, size, twins.beta()),
    );
    ds.drop_training_features();
    let (alpha, beta) = std::thread::scope(|s| {
        let beta = s.spawn(|| train_prepared(pb, &ds, &cfg(Angle::Beta)));
        let alpha = train_prepared(pa, &ds, &cfg(Angle::Alpha));
        (alpha, beta.join())
    });
    let beta =
        beta.map_err(|_| anyhow::anyhow!("the β training thread panicked; see the message above"))?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    plot_curves(&out.join("learning_curves.png"), &[&alpha, &beta])?;
    plot_series(&out.join("test_timeseries.png"), &ds, &[&alpha, &beta], 2)?;
    for t in [&alpha, &beta] {
        println!("{} ({}): float", t.angle.symbol(), t.q.widths());
        print_metrics("float", &t.float_test);
        print_metrics("int8", &t.int_test);
        let v = t.int_val.overall;
        println!(
            "  int8 on the validation flights: MAE {:.3}  RMSE {:.3}  p95 {:.3}  (n={})",
            v.mae, v.rmse, v.p95, v.n
        );
        let ep: f64 = t.curves.epoch_s.iter().sum::<f64>() / t.curves.epoch_s.len().max(1) as f64;
        println!(
            "  mean epoch time {ep:.2} s, best epoch {}",
            t.curves.best_epoch + 1
        );
    }
    let command = command_line();
    let prov = provenance(&ds, args.seed, &command, &fs.name, suite, &alpha, &beta);
    let summary = serde_json::json!({
        "seed": args.seed, "config": size.name(), "features": fs.name, "suite": suite.name(),
        "epochs": epochs, "loss": args.loss.name(),
        "alpha": {"float": alpha.float_test, "int8": alpha.int_test, "int8_val": alpha.int_val, "curves": alpha.curves},
        "beta": {"float": beta.float_test, "int8": beta.int_test, "int8_val": beta.int_val, "curves": beta.curves},
        "provenance": prov,
    });
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    let float = [
        (alpha.part1.as_slice(), alpha.part2.as_slice()),
        (beta.part1.as_slice(), beta.part2.as_slice()),
    ];
    let model =
        trainer::saved::SavedModel::new(&alpha.q, &beta.q, Some(float), suite.name(), &prov)
            .write(out)?;
    println!(
        "wrote {} (score it with `trainer eval --model {}`)",
        model.display(),
        out.display()
    );
    if export {
        export_model(&ds, &alpha.q, &beta.q, &prov, weights_out, vectors_out)?;
    }
    Ok(())
}

/// The flights a `--split` names.
fn parse_split(split: &str) -> Result<Role> {
    Role::from_name(split)
        .with_context(|| format!("--split must be test, train or val, not `{split}`"))
}

/// Refuses frames of `suite` for a model that reads `needs` (`what` names the model).
fn require_suite(what: &str, needs: Suite, suite: Suite) -> Result<()> {
    if !suite.delivers(needs) {
        bail!(
            "{what} reads the `{}` sensor suite; pass --suite {}",
            needs.name(),
            needs.name()
        );
    }
    Ok(())
}

/// `eval-filter --frames`: every flight of `role`, frame by frame ([`trainer::filter_eval::force_frames`]),
/// into the CSV `path`, made whole in memory and written aside, then renamed into place: an error
/// leaves no file.
fn write_force_frames(
    ds: &Dataset,
    role: Role,
    cfg: estimator_core::filter::Config,
    path: &Path,
) -> Result<()> {
    use trainer::filter_eval::{ForceFrame, force_frames};
    let manifest = hil_sim::dataset::Manifest::read(&ds.dir)
        .with_context(|| format!("cannot read the manifest of {}", ds.dir.display()))?;
    let mut text = format!("{}\n", ForceFrame::CSV_HEADER);
    for fl in ds.flights(role) {
        let entry = manifest
            .flights
            .iter()
            .find(|f| f.name == fl.name)
            .with_context(|| format!("{} lists no flight {}", ds.dir.display(), fl.name))?;
        // The dataset keeps only the targets' truth and q̄; the model's point needs all of it.
        let csv = manifest.read_flight(&ds.dir, &entry.file)?;
        let truth: Vec<_> = csv.samples.iter().map(|s| s.truth).collect();
        let rows = force_frames(cfg, &fl.frames, &truth)
            .with_context(|| format!("flight {} of {}", fl.name, ds.dir.display()))?;
        for (i, row) in rows.iter().enumerate() {
            text.push_str(&row.csv_row(&fl.name, i));
            text.push('\n');
        }
    }
    Ok(trainer::files::write_together(&[(path, &text)])?)
}

/// The dataset `trainer eval` reads: any dataset (a `fly` one holds a single test flight), with at
/// least one flight in `role`.
fn load_split(data: &Path, role: Role) -> Result<Dataset> {
    let ds = Dataset::load_any(data, 0.15)
        .with_context(|| format!("cannot load the dataset {}", data.display()))?;
    if ds.flights(role).next().is_none() {
        let have: Vec<&str> = Role::ALL
            .into_iter()
            .filter(|r| ds.flights(*r).next().is_some())
            .map(Role::name)
            .collect();
        if have.is_empty() {
            bail!(
                "{} lists no flight at all: generate a dataset with `hil-sim generate` (or `fly`)",
                data.display()
            );
        }
        bail!(
            "{} has no {} flight; pass --split {}",
            data.display(),
            role.name(),
            have.join(" or --split ")
        );
    }
    if ds.flights(role).all(|f| f.frames.is_empty()) {
        bail!(
            "{}: its {} flights hold no frame to score (their CSVs have no rows): regenerate them",
            data.display(),
            role.name()
        );
    }
    Ok(ds)
}

/// The compiled-in model's provenance and the sensor suite it reads, or the error that says how to
/// get one.
fn compiled_in_model() -> Result<(&'static str, Suite)> {
    match (
        estimator_core::model::SHIPPED_PROVENANCE,
        trainer::pipeline::shipped_suite(),
    ) {
        (Some(prov), Some(suite)) => Ok((prov, suite)),
        _ => bail!(
            "this build ({}) has no compiled-in model: run `trainer train` first with --export (it writes estimator-core/src/model/NAME/weights.rs), or score a trained model with `--model DIR`. A build carries only its own aircraft's networks (docs/aircraft.md)",
            estimator_core::aircraft::AIRCRAFT.name
        ),
    }
}

fn cmd_eval(
    data: &Path,
    split: &str,
    suite: Option<&str>,
    uncertain_hold: u8,
    json: bool,
) -> Result<()> {
    let role = parse_split(split)?;
    let suite = match suite {
        Some(s) => parse_suite(s)?,
        None => trainer::pipeline::shipped_suite().unwrap_or(estimator_core::Suite::Table1),
    };
    let ds = load_split(data, role)?;
    ds.require(suite)?;
    let (prov, needs) = compiled_in_model()?;
    require_suite("the compiled-in model", needs, suite)?;
    let e = eval_shipped(&ds, role, suite, uncertain_hold);
    if json {
        let v = serde_json::json!({
            "model": "shipped (Estimator::shipped, int8)",
            "suite": suite.name(),
            "uncertain_hold_frames": uncertain_hold,
            "split": split,
            "dataset": data.display().to_string(),
            "manifest_sha256": ds.manifest_sha256,
            "alpha": e.alpha, "beta": e.beta,
            "regimes": e.regimes,
            "flagged": e.flagged,
            "sigma": {"alpha": e.sigma[0], "beta": e.sigma[1],
                      "fitted_for_this_model": estimator_core::model::sigma_fitted_for_this_model()},
            "provenance": prov,
        });
        println!("{}", serde_json::to_string(&v)?);
    } else {
        println!("compiled-in model:\n{prov}");
        println!(
            "flights: {split}; sensor suite of the frames: {}",
            suite.name()
        );
        println!("α (deg):");
        print_metrics("int8", &e.alpha);
        println!("β (deg):");
        print_metrics("int8", &e.beta);
        for (name, c) in [("α", &e.sigma[0]), ("β", &e.sigma[1])] {
            println!(
                "{name} within 1σ / 2σ: {:.1} % / {:.1} % of {} frames (median 1σ {:.3}°)",
                100.0 * c.within_1sigma,
                100.0 * c.within_2sigma,
                c.frames,
                c.median_sigma_deg
            );
        }
        if !estimator_core::model::sigma_fitted_for_this_model() {
            println!(
                "note: the 1σ weights were fitted for other networks (scripts/fit-sigma refits them)"
            );
        }
        let r = &e.regimes;
        for (name, m) in [
            ("α, true α < 5°", r.alpha_below_5),
            ("α, true α 5–15°", r.alpha_5_15),
            ("α, true α 15–25°", r.alpha_15_25),
            ("α, true α ≥ 25°", r.alpha_above_25),
            ("β, true |β| < 2°", r.beta_abs_below_2),
            ("β, true |β| ≥ 2°", r.beta_abs_above_2),
        ] {
            println!(
                "  {name:<18} MAE {}  p95 {}  max {}  (n={})",
                m.cell(m.mae, 6),
                m.cell(m.p95, 6),
                m.cell(m.max, 6),
                m.n
            );
        }
        for c in &e.flagged {
            println!(
                "  {}: {} frames not usable (held/no estimate), {} out of envelope, {} in turbulence beyond training, {} with α from the filter, {} with β disagreeing with the filter's, {} with the filter diverging or its measurement rejected, {} uncertain (1σ above its limit), {} with a gyro disagreeing with the EGI, {} with any flag, {} silent (no flag, error > 2° α or > 1° β)",
                c.flight,
                c.not_usable,
                c.out_of_envelope,
                c.turbulence,
                c.alpha_from_filter,
                c.beta_disagrees,
                c.filter_diverged,
                c.uncertain,
                c.gyro_disagrees,
                c.any_flag,
                c.silent
            );
        }
    }
    Ok(())
}

/// `trainer export`: a saved model into the source tree, its test vectors from `data`'s test flights.
fn cmd_export(model: &Path, data: &Path, weights_out: &Path, vectors_out: &Path) -> Result<()> {
    let (qa, qb, model_suite, prov) = trainer::saved::SavedModel::read(model)?;
    let suite = parse_suite(&model_suite)?;
    let ds = Dataset::load_any(data, 0.15)
        .with_context(|| format!("cannot load the dataset {}", data.display()))?;
    ds.require(suite)?;
    // The provenance's first line names the training dataset and its manifest.
    let trained_on = prov.lines().next().unwrap_or("none");
    if trainer::export::provenance_manifest(&prov) != Some(ds.manifest_sha256.as_str()) {
        bail!(
            "{} (manifest sha256 {}) is not the dataset the model in {} was trained with: its provenance begins `{trained_on}`; give that --data",
            data.display(),
            ds.manifest_sha256,
            model.display(),
        );
    }
    if ds.flights(Role::Test).next().is_none() {
        bail!(
            "{} has no test flights: give the --data the model was trained with (its provenance: {trained_on})",
            data.display(),
        );
    }
    export_model(&ds, &qa, &qb, &prov, weights_out, vectors_out)
}

/// Writes the weights and their test vectors (`write_model`) and says where.
fn export_model(
    ds: &Dataset,
    alpha: &trainer::quant::QCascade,
    beta: &trainer::quant::QCascade,
    prov: &str,
    weights_out: &Path,
    vectors_out: &Path,
) -> Result<()> {
    let hash = write_model(ds, alpha, beta, prov, weights_out, vectors_out)?;
    println!(
        "wrote {} (sha256 {hash}) and {}",
        weights_out.display(),
        vectors_out.display()
    );
    Ok(())
}

/// `trainer revector`: the committed vectors' frames, their expected outputs remade.
fn cmd_revector(weights: &Path, vectors: &Path) -> Result<()> {
    let (alpha, beta, _) = trainer::saved::read_generated(weights)?;
    let text = std::fs::read_to_string(vectors)
        .with_context(|| format!("reading the test vectors {}", vectors.display()))?;
    let old = trainer::quant::parse_vectors(&text).with_context(|| {
        format!(
            "{} is not a test-vector file `trainer train --export` wrote",
            vectors.display()
        )
    })?;
    // The header's own lines (not the columns line, which format_vectors writes again).
    let header: Vec<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("# "))
        .filter(|l| !l.starts_with("columns: "))
        .collect();
    let hash = trainer::export::sha256_hex(&std::fs::read_to_string(weights)?);
    if !header
        .iter()
        .any(|l| *l == format!("weights_sha256 {hash}"))
    {
        bail!(
            "{} are the vectors of other weights than {} (no `weights_sha256 {hash}` line): export the model again",
            vectors.display(),
            weights.display()
        );
    }
    let suite = trainer::export::vector_suite(&alpha, &beta);
    let frames: Vec<(bool, estimator_core::SensorFrame)> =
        old.iter().map(|v| (v.reset, v.frame)).collect();
    let new = trainer::quant::vectors(&alpha, &beta, &frames);
    let changed = old.iter().zip(&new).filter(|(o, n)| o != n).count();
    let out = trainer::quant::format_vectors(&new, suite, &header.join("\n"));
    // Written aside and renamed into place: a failure leaves the old file.
    trainer::files::write_together(&[(vectors, &out)])?;
    println!(
        "wrote {}: {} vectors, {changed} with other expected outputs than before",
        vectors.display(),
        new.len()
    );
    Ok(())
}

/// `trainer combine`: the α network of one saved model and the β network of another.
fn cmd_combine(alpha: &Path, beta: &Path, out: &Path) -> Result<()> {
    let model = trainer::saved::SavedModel::combine(alpha, beta)?;
    if out.join("model.json").exists() {
        bail!(
            "{} already holds a model.json: give --out a new directory",
            out.display()
        );
    }
    // Written into a scratch directory inside --out and linked into place, which fails rather than
    // replace a model.json that appeared meanwhile: a failure leaves no partial output.
    let created = !out.exists();
    let scratch = out.join(".combine-partial");
    let path = out.join("model.json");
    let written = (|| -> Result<()> {
        std::fs::create_dir_all(&scratch)?;
        let tmp = model.write(&scratch)?;
        std::fs::hard_link(&tmp, &path)?;
        std::fs::remove_dir_all(&scratch)?;
        Ok(())
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_dir_all(if created { out } else { &scratch });
        return Err(e.context(format!("writing {}", path.display())));
    }
    println!(
        "wrote {} (α of {}, β of {})",
        path.display(),
        alpha.display(),
        beta.display()
    );
    Ok(())
}

/// `trainer eval --model DIR`: a saved model's int8 networks (the integer reference, bit for bit
/// the estimator's kernels) on a split's flights.
fn cmd_eval_model(
    data: &Path,
    models: &[PathBuf],
    split: &str,
    suite: Option<&str>,
    json: bool,
) -> Result<()> {
    let role = parse_split(split)?;
    let (mut qa, mut qb, mut provs, mut suites) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for model in models {
        let (a, b, model_suite, prov) = trainer::saved::SavedModel::read(model)?;
        suites.push(parse_suite(&model_suite)?);
        qa.push(a);
        qb.push(b);
        provs.push(prov);
    }
    let suite = match (suite, suites.first()) {
        (Some(s), _) => parse_suite(s)?,
        (None, Some(s)) => *s,
        (None, None) => bail!("give at least one --model DIR"),
    };
    for (model, model_suite) in models.iter().zip(suites) {
        require_suite(
            &format!("the model in {}", model.display()),
            model_suite,
            suite,
        )?;
    }
    let ds = load_split(data, role)?;
    ds.require(suite)?;
    let alpha = trainer::pipeline::int8_mean_metrics(&qa, &ds, role);
    let beta = trainer::pipeline::int8_mean_metrics(&qb, &ds, role);
    let prov = provs.join("\n");
    let model = models
        .iter()
        .map(|m| m.display().to_string())
        .collect::<Vec<_>>()
        .join(" + ");
    if json {
        let v = serde_json::json!({
            "model": model,
            "suite": suite.name(),
            "split": split,
            "dataset": data.display().to_string(),
            "manifest_sha256": ds.manifest_sha256,
            "alpha": alpha, "beta": beta,
            "provenance": prov,
        });
        println!("{}", serde_json::to_string(&v)?);
    } else {
        println!("model {model} (int8 networks, no flags or fallbacks):\n{prov}");
        println!("flights: {split}; sensor suite: {}", suite.name());
        println!("α (deg):");
        print_metrics("int8", &alpha);
        println!("β (deg):");
        print_metrics("int8", &beta);
    }
    Ok(())
}

fn cmd_fit_sigma(
    data: &[PathBuf],
    every: usize,
    out: &Path,
    rows_csv: Option<&Path>,
    json: bool,
) -> Result<()> {
    use trainer::uncertainty::{Rows, fit, rust_file};
    if every == 0 {
        bail!("--every must be at least 1");
    }
    let (prov, suite) = compiled_in_model()?;
    let mut datasets = Vec::new();
    for d in data {
        let ds = Dataset::load_any(d, 0.15)
            .with_context(|| format!("cannot load the dataset {}", d.display()))?;
        ds.require(suite)?;
        datasets.push(ds);
    }
    let all = |ds: &Dataset| Role::ALL.into_iter().flat_map(|r| ds.flights(r)).count();
    let flights: usize = datasets.iter().map(all).sum();
    let bar = indicatif::ProgressBar::new(flights as u64);
    hil_sim::progress::style(&bar, "flights");
    hil_sim::progress::log_when_not_a_terminal(&bar, "flights");
    let mut rows: [Rows; 2] = Default::default();
    let mut per_dataset: Vec<[Rows; 2]> = Vec::new();
    let mut flight_names: Vec<Vec<String>> = Vec::new();
    for ds in &datasets {
        let mut mine: [Rows; 2] = Default::default();
        let mut flights_here = Vec::new();
        for fl in Role::ALL.into_iter().flat_map(|r| ds.flights(r)) {
            let ans = trainer::pipeline::shipped_answers(fl, suite);
            let index = u32::try_from(flights_here.len()).unwrap_or(u32::MAX);
            flights_here.push(fl.name.clone());
            let [a, b] = trainer::pipeline::sigma_rows(
                &ans,
                [
                    fl.truth(trainer::data::Target::AlphaDeg),
                    fl.truth(trainer::data::Target::BetaDeg),
                ],
                index,
            );
            mine[0].extend(a);
            mine[1].extend(b);
            bar.inc(1);
        }
        rows[0].extend(mine[0].clone());
        rows[1].extend(mine[1].clone());
        per_dataset.push(mine);
        flight_names.push(flights_here);
    }
    bar.finish_and_clear();
    let (alpha, beta) = (fit(&rows[0].every(every))?, fit(&rows[1].every(every))?);
    let names: Vec<String> = data.iter().map(|d| d.display().to_string()).collect();
    if let Some(path) = rows_csv {
        trainer::uncertainty::write_rows(path, &names, &flight_names, &per_dataset)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    // Each dataset's coverage under the fitted weights: the fit pools them, a user flies one.
    let each: Vec<serde_json::Value> = names
        .iter()
        .zip(&per_dataset)
        .map(|(name, [a, b])| {
            let cov = |r: &Rows, w| trainer::uncertainty::coverage_with(w, r);
            serde_json::json!({"data": name, "alpha": cov(a, &alpha.weights), "beta": cov(b, &beta.weights)})
        })
        .collect();
    let first_line = prov.lines().next().unwrap_or("");
    let (ca, cb) = (
        trainer::uncertainty::coverage_with(&alpha.weights, &rows[0]),
        trainer::uncertainty::coverage_with(&beta.weights, &rows[1]),
    );
    let provenance = format!(
        "command: {}\nflights: {flights} (every flight of {}; fitted on every {every}th frame)\nestimator: {first_line}\n\
         alpha: {} frames, 1σ median {:.3} deg, within 1σ {:.1} %, within 2σ {:.1} %\n\
         beta: {} frames, 1σ median {:.3} deg, within 1σ {:.1} %, within 2σ {:.1} %\n",
        command_line(),
        names.join(", "),
        ca.frames,
        ca.median_sigma_deg,
        100.0 * ca.within_1sigma,
        100.0 * ca.within_2sigma,
        cb.frames,
        cb.median_sigma_deg,
        100.0 * cb.within_1sigma,
        100.0 * cb.within_2sigma,
    );
    let text = rust_file(&alpha, &beta, &provenance, prov);
    trainer::files::write_together(&[(out, &text)])?;
    if json {
        let v = serde_json::json!({"alpha": alpha, "beta": beta, "flights": flights, "datasets": each, "out": out.display().to_string()});
        println!("{}", serde_json::to_string(&v)?);
    } else {
        print!("{provenance}");
        println!("within 2σ, dataset by dataset (α / β):");
        for e in &each {
            println!(
                "  {}: {:.1} % / {:.1} %",
                e["data"].as_str().unwrap_or(""),
                100.0 * e["alpha"]["within_2sigma"].as_f64().unwrap_or(f64::NAN),
                100.0 * e["beta"]["within_2sigma"].as_f64().unwrap_or(f64::NAN)
            );
        }
        println!(
            "wrote {}: rebuild (cargo build --release) for the estimator to carry it",
            out.display()
        );
    }
    Ok(())
}

/// `trainer finetune`: the model in `model` trained further on the flight test in `ft`.
fn parse_tune(s: &str) -> std::result::Result<trainer::finetune::Tune, String> {
    match s {
        "all" => Ok(trainer::finetune::Tune::All),
        "output" => Ok(trainer::finetune::Tune::Output),
        _ => Err(format!("`{s}`: choose all or output")),
    }
}

fn cmd_finetune(
    model: &Path,
    ft: &Path,
    out: &Path,
    replay: Option<&Path>,
    tune: trainer::finetune::Tune,
    cfg: TrainConfig,
    json: bool,
) -> Result<()> {
    if out.join("model.json").exists() {
        bail!(
            "{} holds a model.json already: choose another --out, or delete it",
            out.display()
        );
    }
    let ([fa, fb], model_suite, prov) = trainer::saved::SavedModel::read_float(model)
        .with_context(|| format!("reading the model in {}", model.display()))?;
    let needs = parse_suite(&model_suite)
        .with_context(|| format!("the sensor suite of the model in {}", model.display()))?;
    let manifest = hil_sim::dataset::Manifest::read(ft)
        .with_context(|| format!("reading the flight test {}", ft.display()))?;
    let delivers = manifest
        .suites
        .iter()
        .filter_map(|s| estimator_core::Suite::from_name(s))
        .any(|s| s.delivers(needs));
    if !delivers {
        bail!(
            "{} records the sensor suites {:?}; the model reads `{}`: regenerate it with this build's `hil-sim generate --preset flight-test`",
            ft.display(),
            manifest.suites,
            needs.name()
        );
    }
    let data = trainer::finetune::boom_targets(ft)
        .with_context(|| format!("reading the boom's air data of {}", ft.display()))?;
    let replay_ds = replay.map(|d| load(d, 0.15)).transpose()?;
    if let Some(ds) = &replay_ds
        && !ds.suites.iter().any(|s| s.delivers(needs))
    {
        bail!(
            "--replay {} does not carry the `{}` suite the model reads: give the dataset the model trained on",
            ds.dir.display(),
            needs.name()
        );
    }
    let replay_flights: Vec<&trainer::data::Flight> = replay_ds
        .as_ref()
        .map(|ds| ds.flights(trainer::data::Role::Train).collect())
        .unwrap_or_default();
    let rows = |fl: &[trainer::data::Flight]| fl.iter().map(|f| f.len()).sum::<usize>();
    eprintln!(
        "flight test {}: {} training frames, {} held out (blocks of {} s), {} left out",
        ft.display(),
        rows(&data.train),
        rows(&data.val),
        trainer::finetune::BLOCK_S,
        data.skipped
    );
    let bars = indicatif::MultiProgress::new();
    let cfg_of = |a: Angle| TrainConfig {
        label: a.name().into(),
        bars: Some(bars.clone()),
        ..cfg.clone()
    };
    let (alpha, beta) = std::thread::scope(|s| {
        let beta = s.spawn(|| {
            trainer::finetune::finetune(&fb, &data, &replay_flights, tune, &cfg_of(Angle::Beta))
        });
        let alpha =
            trainer::finetune::finetune(&fa, &data, &replay_flights, tune, &cfg_of(Angle::Alpha));
        (alpha, beta.join())
    });
    let beta = beta
        .map_err(|_| anyhow::anyhow!("the β fine-tuning thread panicked; see the message above"))?;
    let command = command_line();
    let angle_json = |t: &trainer::finetune::Tuned| {
        serde_json::json!({
            "improved": t.improved,
            "val_loss_before": t.val_before,
            "best_epoch": t.curves.best_epoch + 1,
            "val_boom_mae_deg_before": t.val_mae_deg[0],
            "val_boom_mae_deg_after": t.val_mae_deg[1],
            "curves": t.curves,
        })
    };
    let summary = serde_json::json!({
        "model": model.display().to_string(),
        "flight_test": ft.display().to_string(),
        "epochs": cfg.epochs, "lr": cfg.lr, "batch": cfg.batch, "seed": cfg.seed, "loss": cfg.loss.name(),
        "tune": format!("{tune:?}").to_lowercase(),
        "replay": replay.map(|d| d.display().to_string()),
        "train_frames": rows(&data.train), "val_frames": rows(&data.val), "skipped_frames": data.skipped,
        "alpha": angle_json(&alpha), "beta": angle_json(&beta),
        "command": command,
    });
    let prov = format!(
        "{prov}fine-tuned on the flight test {} (manifest sha256 {}; the boom's air data, {} frames, {} held out), epochs {}, lr {}, seed {}, {tune:?} parameters{}\ncommand: {command}\n",
        ft.display(),
        hil_sim::dataset::sha256_file(&ft.join("manifest.json"))
            .with_context(|| format!("hashing {}/manifest.json", ft.display()))?,
        rows(&data.train),
        rows(&data.val),
        cfg.epochs,
        cfg.lr,
        cfg.seed,
        replay_ds.as_ref().map_or(String::new(), |d| format!(
            ", replaying the training flights of {} (manifest sha256 {})",
            d.dir.display(),
            d.manifest_sha256
        ))
    );
    let float = [
        (alpha.part1.as_slice(), alpha.part2.as_slice()),
        (beta.part1.as_slice(), beta.part2.as_slice()),
    ];
    let saved =
        trainer::saved::SavedModel::new(&alpha.q, &beta.q, Some(float), &model_suite, &prov);
    // Both files are written into a scratch directory inside --out and moved into place: a failure
    // leaves no partial output.
    let created = !out.exists();
    let scratch = out.join(".finetune-partial");
    let written = (|| -> Result<()> {
        std::fs::create_dir_all(&scratch)?;
        std::fs::write(
            scratch.join("summary.json"),
            serde_json::to_string_pretty(&summary)?,
        )?;
        saved.write(&scratch)?;
        for f in ["summary.json", "model.json"] {
            std::fs::rename(scratch.join(f), out.join(f))?;
        }
        std::fs::remove_dir(&scratch)?;
        Ok(())
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_dir_all(if created { out } else { &scratch });
        return Err(e.context(format!("writing {}", out.display())));
    }
    let path = out.join("model.json");
    if json {
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        for (a, t) in [(Angle::Alpha, &alpha), (Angle::Beta, &beta)] {
            println!(
                "{}: held-out int8 MAE against the boom {:.3}° → {:.3}° ({})",
                a.symbol(),
                t.val_mae_deg[0],
                t.val_mae_deg[1],
                if t.improved {
                    format!("epoch {} kept", t.curves.best_epoch + 1)
                } else {
                    "no epoch beat the model: kept as it was".into()
                }
            );
        }
        println!(
            "wrote {} (score it with `trainer eval --model {}`)",
            path.display(),
            out.display()
        );
    }
    Ok(())
}

fn cmd_calibrate(
    ft: &Path,
    model_ft: &[PathBuf],
    moment_ft: &[PathBuf],
    first: Option<&Path>,
    out: &Path,
    json: bool,
) -> Result<()> {
    let t0 = std::time::Instant::now();
    if model_ft.is_empty() && !moment_ft.is_empty() {
        bail!(
            "--moment-flight-test needs --model-flight-test: the aircraft the moment cards fly is the calibrated aircraft of a first trainer calibrate --model-flight-test CARD ..., and the lift, drag and thrust stay over the model cards"
        );
    }
    let carries = match first {
        Some(f) => trainer::calibrate::carried_scales(f)
            .with_context(|| format!("reading the first calibration {}", f.display()))?,
        None => trainer::calibrate::Carried::MODEL,
    };
    trainer::calibrate::check_model_cards(ft, model_ft)
        .with_context(|| format!("checking the model cards against {}", ft.display()))?;
    trainer::calibrate::check_model_cards(ft, moment_ft)
        .with_context(|| format!("checking the moment cards against {}", ft.display()))?;
    let c = trainer::calibrate::calibrate(ft, None)
        .with_context(|| format!("calibrating from {}", ft.display()))?;
    let cards = |dirs: &[PathBuf], what: &str| {
        dirs.iter()
            .map(|d| {
                trainer::calibrate::calibrate(d, Some(c.structure))
                    .with_context(|| format!("identifying the {what} {}", d.display()))
            })
            .collect::<Result<Vec<_>>>()
    };
    let model_cards = cards(model_ft, "model card")?;
    let moment_cards = cards(moment_ft, "moment card")?;
    let r = trainer::calibrate::Report::new(c, model_cards, moment_cards, carries);
    let spec = trainer::calibrate::spec_toml(&r, ft);
    let md =
        trainer::calibrate::markdown(&r, &command_line(), &machine(), t0.elapsed().as_secs_f64());
    let text = serde_json::to_string_pretty(&r)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    std::fs::write(out.join("calibration.json"), &text)?;
    // The same calibrated aircraft keeps its file and its time: scripts/calibrate rebuilds the
    // aircraft and its estimator only when the spec is newer.
    let spec_path = out.join("aircraft.toml");
    if std::fs::read_to_string(&spec_path).ok().as_deref() != Some(spec.as_str()) {
        std::fs::write(&spec_path, spec)?;
    }
    std::fs::write(out.join("calibration.md"), md)?;
    if json {
        println!("{}", serde_json::to_string(&r)?);
    } else {
        let (l, o, sb, sc) = (
            &r.scales.lift,
            &r.scales.offset,
            &r.scales.sideslip,
            &r.scales.side_controls,
        );
        let flap = r.scales.flap.map_or(String::new(), |f| {
            format!(", flap-lift scale {:.4} ± {:.4}", f.value, f.std_error)
        });
        println!(
            "lift scale {:.4} ± {:.4}{flap}, lift offset {:+.4} ± {:.4}, side-force scale {:.4} ± {:.4} (sideslip terms) and {:.4} ± {:.4} (surface and rate terms) ({} flights{}); wrote {}/calibration.md, calibration.json, aircraft.toml",
            l.value,
            l.std_error,
            o.value,
            o.std_error,
            sb.value,
            sb.std_error,
            sc.value,
            sc.std_error,
            r.flight_test.flights.len(),
            match (&r.model_card, &r.moment_card) {
                (Some(_), Some(_)) =>
                    ", over the model card's; the side force over the moment card's",
                (Some(_), None) => ", over the model card's",
                _ => "",
            },
            out.display()
        );
        println!("{}", trainer::calibrate::drag_line(&r));
        println!("{}", trainer::calibrate::moments_line(&r));
    }
    Ok(())
}

/// `CONFIG` with the `--tune` overrides.
fn filter_config(tune: &str) -> Result<estimator_core::filter::Config> {
    let mut c = estimator_core::filter::CONFIG;
    for kv in tune.split(',').filter(|s| !s.is_empty()) {
        let (k, v) = kv
            .split_once('=')
            .with_context(|| format!("--tune: `{kv}` is not key=value"))?;
        let v: f32 = v
            .parse()
            .with_context(|| format!("--tune: `{v}` is not a number"))?;
        // Each key's value is refused outside its range: `v` if finite and `holds`.
        let check = |holds: fn(f32) -> bool, range: &str| -> Result<f32> {
            if v.is_finite() && holds(v) {
                Ok(v)
            } else {
                bail!("--tune: {k}={v}: {k} must be {range}")
            }
        };
        // A time constant divides, a measurement 1σ is inverted, a gate and a flag limit of 0
        // would refuse every update or raise every flag.
        let positive = || check(|v| v > 0.0, "more than 0");
        // Spectral densities, initial 1σ and delays: 0 holds the state, or takes no delay.
        let non_negative = || check(|v| v >= 0.0, "0 or more");
        match k {
            "gust_sigma" => c.gust_sigma = non_negative()?,
            "gust_tau_s" => c.gust_tau_s = positive()?,
            "accel_sigma_y" => c.accel_sigma[0] = positive()?,
            "accel_sigma_z" => c.accel_sigma[1] = positive()?,
            "accel_delay_s" => c.accel_delay_s = non_negative()?,
            "gate" => c.gate = positive()?,
            "max_sigma_rad" => c.max_sigma_rad = positive()?,
            "mean_wind_psd_h" => c.mean_wind_psd[..2].fill(non_negative()?),
            "mean_wind_psd_d" => c.mean_wind_psd[2] = non_negative()?,
            "mean_wind_sigma0_d" => c.mean_wind_sigma0[2] = non_negative()?,
            "lift_scale_psd" => c.lift_scale_psd = non_negative()?,
            "gear_norm" => {
                c.gear_norm = check(|v| (0.0..=1.0).contains(&v), "between 0 (up) and 1 (down)")?
            }
            "lift_scale_sigma0" => c.lift_scale_sigma0 = non_negative()?,
            "side_scale_psd" => c.side_scale_psd = non_negative()?,
            "side_scale_sigma0" => c.side_scale_sigma0 = non_negative()?,
            "te_lift_sigma0" | "te_lift_psd" if !estimator_core::filter::LEARNS_TE_LIFT => bail!(
                "--tune: {k} needs a filter with the trailing-edge lift state: build with ESTIMATOR_FILTER_TE_LIFT=on (not off), or for a description whose filter.te_lift_sigma0 or te_lift_psd is above 0"
            ),
            "te_lift_sigma0" => c.te_lift_sigma0 = non_negative()?,
            "te_lift_psd" => c.te_lift_psd = non_negative()?,
            "subsamples" => {
                let v = check(
                    |v| v == 0.0 || v == 1.0 || v == 2.0,
                    "0 (off), 1 (latest) or 2 (period mean)",
                )?;
                c.subsamples = match v as u8 {
                    0 => estimator_core::filter::SubsampleUse::Off,
                    1 => estimator_core::filter::SubsampleUse::Latest,
                    _ => estimator_core::filter::SubsampleUse::Mean,
                }
            }
            "r_adapt_tau_s" => c.r_adapt_tau_s = non_negative()?,
            "r_adapt_lo_y" => c.r_adapt_range[0][0] = positive()?,
            "r_adapt_hi_y" => c.r_adapt_range[0][1] = positive()?,
            "r_adapt_lo_z" => c.r_adapt_range[1][0] = positive()?,
            "r_adapt_hi_z" => c.r_adapt_range[1][1] = positive()?,
            other => bail!("--tune: unknown key `{other}` (see trainer eval-filter --help)"),
        }
    }
    if !(c.r_adapt_tau_s.is_finite() && c.r_adapt_tau_s >= 0.0) {
        bail!("--tune: r_adapt_tau_s must be 0 (off) or a positive number of seconds");
    }
    for [lo, hi] in c.r_adapt_range {
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
            bail!("--tune: r_adapt_lo_* and r_adapt_hi_* need 0 < lo ≤ hi (got {lo}, {hi})");
        }
    }
    Ok(c)
}

fn cmd_sweep(g: &SweepGrid, action: &SweepAction) -> Result<()> {
    use trainer::sweep::{Grid, JobResult, Scores, merge, write_result};
    // Every name of the grid is checked before a job is listed, run or merged.
    for c in &g.sizes {
        Size::parse(c).with_context(|| format!("--config `{c}`: {}", Size::choices()))?;
    }
    for f in &g.features {
        FeatureSet::parse(f).with_context(|| format!("--features `{f}`"))?;
    }
    for s in &g.suites {
        parse_suite(s).with_context(|| format!("--suite `{s}`"))?;
    }
    for (flag, names) in [
        ("--config", &g.sizes),
        ("--features", &g.features),
        ("--suite", &g.suites),
    ] {
        let mut seen = std::collections::BTreeSet::new();
        if let Some(n) = names.iter().find(|n| !seen.insert(n.as_str())) {
            bail!("{flag} `{n}` is repeated: give each once");
        }
    }
    let grid = Grid {
        sizes: g.sizes.clone(),
        features: g.features.clone(),
        suites: g.suites.clone(),
        seeds: g.seeds.0.clone(),
    };
    let jobs = grid.jobs();
    if action.list {
        println!("jobs: {}", jobs.len());
        for j in &jobs {
            println!("{}: {} seed {}", j.index, j.config(), j.seed);
        }
        return Ok(());
    }
    if action.merge {
        let m = merge(&grid, &g.out)?;
        let path = g.out.join("sweep.md");
        std::fs::write(&path, m.markdown(&command_line(), &machine()))
            .with_context(|| format!("cannot write {}", path.display()))?;
        println!(
            "{} jobs: {} finished, {} failed, {} missing; wrote {}",
            jobs.len(),
            m.done.len(),
            m.failed.len(),
            m.missing.len(),
            path.display()
        );
        if !m.failed.is_empty() || !m.missing.is_empty() {
            bail!(
                "{} of {} jobs failed or left no result; they are named in {}",
                m.failed.len() + m.missing.len(),
                jobs.len(),
                path.display()
            );
        }
        return Ok(());
    }
    let k = action.job.unwrap_or(0);
    let job = jobs
        .get(k)
        .cloned()
        .with_context(|| format!("--job {k}: the grid has jobs 0..{}", jobs.len()))?;
    let t0 = std::time::Instant::now();
    let run = || -> Result<Scores> {
        let size = Size::parse(&job.size)
            .with_context(|| format!("size `{}`: {}", job.size, Size::choices()))?;
        let suite = parse_suite(&job.suite)?;
        let fs = FeatureSet::parse(&job.features)?;
        fs.check_suite(suite)?;
        let ds = load(&g.data, g.val_fraction)?;
        ds.require(suite)?;
        let cfg = |angle: Angle| TrainConfig {
            epochs: g.epochs.unwrap_or(size.default_epochs()),
            batch: g.batch,
            lr: g.lr,
            seed: job.seed,
            label: format!("job {k} {}", angle.name()),
            progress: false,
            loss: g.loss,
            replicas: None,
            bars: None,
        };
        let a = train_angle(
            &ds,
            Angle::Alpha,
            fs.for_angle(Angle::Alpha),
            size,
            &cfg(Angle::Alpha),
        );
        let b = train_angle(
            &ds,
            Angle::Beta,
            fs.for_angle(Angle::Beta),
            size,
            &cfg(Angle::Beta),
        );
        Ok(Scores {
            alpha_float: a.float_test.overall,
            alpha_int8: a.int_test.overall,
            beta_float: b.float_test.overall,
            beta_int8: b.int_test.overall,
        })
    };
    let outcome = run();
    let result = JobResult {
        job: job.clone(),
        scores: outcome.as_ref().ok().cloned(),
        error: outcome.as_ref().err().map(|e| format!("{e:#}")),
        seconds: t0.elapsed().as_secs_f64(),
    };
    let path = write_result(&g.out, &result)?;
    match outcome {
        Ok(s) => {
            println!(
                "job {k} ({}, seed {}): α {:.3}/{:.3}, β {:.3}/{:.3} (float/int8 MAE) in {:.1} s; wrote {}",
                job.config(),
                job.seed,
                s.alpha_float.mae,
                s.alpha_int8.mae,
                s.beta_float.mae,
                s.beta_int8.mae,
                result.seconds,
                path.display()
            );
            Ok(())
        }
        Err(e) => Err(e.context(format!(
            "job {k} ({}, seed {}) failed; recorded in {}",
            job.config(),
            job.seed,
            path.display()
        ))),
    }
}

#[derive(serde::Deserialize)]
struct BarsSpec {
    series: Vec<String>,
    panels: Vec<BarsPanel>,
}

#[derive(serde::Deserialize)]
struct BarsPanel {
    title: String,
    xlabel: String,
    rows: Vec<(String, Vec<f64>)>,
}

#[derive(serde::Deserialize)]
struct LinesSpec {
    panels: Vec<LinesPanel>,
}

#[derive(serde::Deserialize)]
struct LinesPanel {
    title: String,
    xlabel: String,
    ylabel: String,
    series: Vec<LinesSeries>,
}

#[derive(serde::Deserialize)]
struct LinesSeries {
    name: String,
    points: Vec<(f64, f64)>,
}

/// A plot command's JSON description at `spec`, or an error that names the shape it expects.
fn read_spec<T: serde::de::DeserializeOwned>(spec: &Path, shape: &str) -> Result<T> {
    let text =
        std::fs::read_to_string(spec).with_context(|| format!("cannot read {}", spec.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: expected {shape}", spec.display()))
}

/// A plot command's `--out`: a `.png` file (the image format follows the name) in a directory that
/// exists, checked before the spec is read.
fn png_out(out: &Path) -> Result<()> {
    if !out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        bail!(
            "--out {}: the plot is a PNG; give a file name ending in .png",
            out.display()
        );
    }
    if out.is_dir() {
        bail!(
            "--out {} is a directory; give the PNG file to write",
            out.display()
        );
    }
    let parent = out.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = parent.filter(|p| !p.is_dir()) {
        bail!(
            "--out {}: the directory {} does not exist; create it first",
            out.display(),
            dir.display()
        );
    }
    Ok(())
}

fn cmd_lines(spec: &Path, out: &Path) -> Result<()> {
    png_out(out)?;
    let s: LinesSpec = read_spec(
        spec,
        r#"{"panels": [{"title", "xlabel", "ylabel", "series": [{"name", "points": [[x, y]]}]}]}"#,
    )?;
    if s.panels.is_empty() {
        bail!("{}: no panel to draw", spec.display());
    }
    if let Some(p) = s
        .panels
        .iter()
        .find(|p| p.series.iter().all(|l| l.points.is_empty()))
    {
        bail!(
            "{}: panel `{}` has no point to draw",
            spec.display(),
            p.title
        );
    }
    let panels: Vec<_> = s
        .panels
        .iter()
        .map(|p| {
            let series = p
                .series
                .iter()
                .map(|l| trainer::plots::Series {
                    name: l.name.clone(),
                    points: &l.points,
                })
                .collect();
            (
                p.title.clone(),
                p.xlabel.as_str(),
                p.ylabel.as_str(),
                false,
                series,
            )
        })
        .collect();
    trainer::plots::line_panels(out, &panels, 520, 400)
        .with_context(|| format!("cannot draw {}", out.display()))?;
    Ok(())
}

fn cmd_bars(spec: &Path, out: &Path) -> Result<()> {
    png_out(out)?;
    let s: BarsSpec = read_spec(
        spec,
        r#"{"series": [..], "panels": [{"title", "xlabel", "rows": [[label, [values]]]}]}"#,
    )?;
    if s.panels.is_empty() {
        bail!("{}: no panel to draw", spec.display());
    }
    if let Some(p) = s
        .panels
        .iter()
        .find(|p| p.rows.iter().any(|r| r.1.len() != s.series.len()))
    {
        bail!(
            "{}: panel `{}` has a row without one value per series ({})",
            spec.display(),
            p.title,
            s.series.len()
        );
    }
    let panels: Vec<trainer::plots::BarPanel> = s
        .panels
        .iter()
        .map(|p| (p.title.clone(), p.xlabel.as_str(), p.rows.clone()))
        .collect();
    trainer::plots::grouped_bar_panels(out, &panels, &s.series)
        .with_context(|| format!("cannot draw {}", out.display()))?;
    Ok(())
}

/// The `ood` preset's dataset at `data`: another preset's flights have no twins and no cases, and
/// would give a table of NaN.
fn load_ood(data: &Path) -> Result<Dataset> {
    let ds = Dataset::load_any(data, 0.0)
        .with_context(|| format!("cannot load the OOD dataset {}", data.display()))?;
    if ds.preset != "ood" {
        bail!(
            "{} is a `{}` dataset, not an `ood` one: its flights have no in-distribution twins to \
             compare with; generate one with `hil-sim generate --preset ood --out DIR`",
            data.display(),
            ds.preset
        );
    }
    Ok(ds)
}

fn cmd_ood(data: &Path, out: &Path, json: bool) -> Result<()> {
    let t0 = std::time::Instant::now();
    let ds = load_ood(data)?;
    let r = trainer::ood::run(&ds);
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let md = format!(
        "# Out-of-distribution flights (generated by `trainer ood`)\n\n\
         Command: `hil-sim generate --preset ood --seed 1 --out {0}` then `trainer ood --data {0} --out {1}`  \n\
         Machine: {2}; {3:.1} s wall. Model: {4}\n\n{5}",
        data.display(),
        out.display(),
        machine(),
        t0.elapsed().as_secs_f64(),
        r.model
            .as_deref()
            .map(trainer::export::provenance_data)
            .unwrap_or_else(|| "none compiled in".to_string()),
        trainer::ood::markdown(&r)
    );
    let md_path = out.join("ood.md");
    std::fs::write(&md_path, md).with_context(|| format!("cannot write {}", md_path.display()))?;
    let json_path = out.join("ood.json");
    let text = serde_json::to_string_pretty(&r)?;
    std::fs::write(&json_path, &text)
        .with_context(|| format!("cannot write {}", json_path.display()))?;
    trainer::ood::plot(&r, &out.join("ood.png"))?;
    if json {
        println!("{}", serde_json::to_string(&r)?);
    } else {
        print!("{}", trainer::ood::markdown(&r));
        println!(
            "wrote {}, {} and {}",
            md_path.display(),
            json_path.display(),
            out.join("ood.png").display()
        );
    }
    Ok(())
}

fn cmd_eval_filter(
    data: &Path,
    split: &str,
    tune: &str,
    json: bool,
    frames: Option<&Path>,
) -> Result<()> {
    use trainer::filter_eval::eval_filter;
    let role = parse_split(split)?;
    // Any dataset with flights of that split (a test-only one from `generate --test-only` too).
    let ds = load_split(data, role)?;
    let cfg = filter_config(tune)?;
    if let Some(path) = frames {
        write_force_frames(&ds, role, cfg, path)?;
    }
    let e = eval_filter(&ds, role, cfg);
    if json {
        let v = serde_json::json!({
            "model": "filter (estimator_core::filter::CONFIG, f32)",
            "tune": tune,
            "suite": "egi",
            "split": split,
            "dataset": data.display().to_string(),
            "manifest_sha256": ds.manifest_sha256,
            "alpha": e.alpha, "beta": e.beta,
            "alpha_trusted": e.alpha_trusted, "beta_trusted": e.beta_trusted,
            "flags": e.flags,
            "beta_gain_error": e.beta_gain_error,
        });
        println!("{}", serde_json::to_string(&v)?);
    } else {
        println!("model-based filter, {split} flights, every frame:");
        println!("α (deg):");
        print_metrics("filter", &e.alpha);
        println!("β (deg):");
        print_metrics("filter", &e.beta);
        println!(
            "β gain error {:+.1} % (the slope of the β error over the true β)",
            100.0 * e.beta_gain_error
        );
        println!("frames with no flag raised:");
        print_metrics("α trusted", &e.alpha_trusted);
        print_metrics("β trusted", &e.beta_trusted);
        for s in &e.flags {
            let te = if estimator_core::filter::LEARNS_TE_LIFT {
                format!(", trailing-edge lift s {:+.3}", s.final_te_lift)
            } else {
                String::new()
            };
            println!(
                "  {}: no input {:.1} %, gated {:.1} %, low confidence {:.1} %, {} restarts, mean 1σ α {:.3}° β {:.3}°, β gain error {:+.1} %, scales at the end: lift {:.3}, side force {:.3}{te}",
                s.flight,
                100.0 * s.no_input,
                100.0 * s.gated,
                100.0 * s.low_confidence,
                s.restarted,
                s.mean_sigma_alpha_deg,
                s.mean_sigma_beta_deg,
                100.0 * s.beta_gain_error,
                s.final_lift_scale,
                s.final_side_scale
            );
        }
    }
    Ok(())
}

fn cmd_baselines(args: &TrainArgs, gb_rows: usize) -> Result<()> {
    use trainer::baselines::{Baseline, run_baseline};
    let size = args.size()?;
    let (suite, fs) = args.suite_features()?;
    let ds = args.dataset(suite)?;
    for angle in [Angle::Alpha, Angle::Beta] {
        let feats = fs.for_angle(angle);
        for kind in [Baseline::Linear, Baseline::GradientBoosting, Baseline::Mlp] {
            let cfg = args.train_config(size, format!("{} mlp", angle.name()), false);
            let t0 = std::time::Instant::now();
            let m = run_baseline(
                kind,
                &ds,
                angle,
                feats,
                size.hidden(angle),
                &cfg,
                gb_rows,
                &[],
            )?
            .metrics;
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

fn cmd_report(r: &ReportArgs) -> Result<()> {
    let (args, seeds, ablation, gb_rows, out, json, shipped_rows) = (
        &r.args,
        r.seeds.0.clone(),
        r.ablation.as_str(),
        r.gb_rows,
        r.out.as_path(),
        r.json,
        r.shipped_rows,
    );
    let ood = r.ood.as_deref();
    use trainer::report::{BenchEpoch, ReportConfig, run};
    let size = args.size()?;
    let (suite, features) = args.suite_features()?;
    let ablation = match ablation {
        "none" => None,
        a => {
            let a = FeatureSet::parse(a)?;
            a.check_suite(suite)?;
            Some(a)
        }
    };
    let ds = args.dataset(suite)?;
    let epochs = args.epochs(size);
    let cfg = ReportConfig {
        seeds,
        size,
        epochs,
        batch: args.batch,
        lr: args.lr,
        gb_rows,
        features,
        ablation: ablation.clone(),
        suite,
        shipped_rows: if shipped_rows {
            ds.require(Suite::Egi120)?;
            // The configuration the shipped weights were trained with (their PROVENANCE).
            let hybrid = FeatureSet::parse(SHIPPED_FEATURES)?;
            hybrid.check_suite(Suite::Egi120)?;
            let size = Size::parse(estimator_core::aircraft::AIRCRAFT.estimator.config)
                .context("the aircraft's estimator.config is no network size")?;
            Some((hybrid, size, Loss::L1))
        } else {
            None
        },
        // A killed run leaves its finished rows here; the next run with the same settings resumes.
        progress_file: Some(out.join(".report-progress.jsonl")),
    };
    // Every input is read before --out is made: a missing one leaves nothing behind.
    let ood = ood.map(load_ood).transpose()?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let report = run(
        &ds,
        ood.as_ref(),
        &cfg,
        |a, b| {
            plot_curves(&out.join("training_learning_curves.png"), &[a, b])?;
            plot_series(
                &out.join("training_test_timeseries_alpha.png"),
                &ds,
                &[a],
                2,
            )?;
            plot_series(&out.join("training_test_timeseries_beta.png"), &ds, &[b], 2)
        },
        |line| eprintln!("{line}"),
    )?;
    report.pictures(&ds, out)?;
    if json {
        println!("{}", serde_json::to_string(&report)?);
    }
    let bench_path = out.join("bench_epoch.json");
    let bench: Option<BenchEpoch> = match std::fs::read_to_string(&bench_path) {
        Ok(text) => Some(serde_json::from_str(&text).with_context(|| {
            format!(
                "{} is not JSON: rerun `trainer bench-epoch`",
                bench_path.display()
            )
        })?),
        Err(_) => None,
    };
    let mut md = report.markdown(
        &command_line(),
        &machine(),
        ablation.as_ref().map(|a| a.name.as_str()),
        bench.as_ref(),
    );
    if let Some(o) = &ood {
        md.push_str(&report.ood_markdown(o));
    }
    std::fs::write(out.join("training.md"), md)
        .with_context(|| format!("writing {}", out.join("training.md").display()))?;
    // The report is written: its finished rows are no longer needed for a resume.
    if let Some(p) = &cfg.progress_file {
        let _ = std::fs::remove_file(p);
    }
    eprintln!("wrote {}/training.md and PNGs", out.display());
    Ok(())
}

/// Features in the Spearman heatmap (besides the targets): beyond about 40 labels it is unreadable.
const HEATMAP_FEATURES: usize = 36;

struct ShapArgs {
    seed: u64,
    explain: usize,
    background: usize,
    permutations: usize,
}

fn cmd_features(data: &Path, out: &Path, rows: usize, shap: &ShapArgs) -> Result<()> {
    use std::fmt::Write;
    use trainer::analysis::{columns, spearman_matrix};
    let ds = load(data, 0.15)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let (names, cols) = columns(&ds, rows);
    let n_rows = cols.first().map(|c| c.len()).unwrap_or(0);
    eprintln!(
        "Spearman over {} columns × {n_rows} training rows",
        names.len()
    );
    let m = spearman_matrix(&cols);
    let mut csv = format!(",{}\n", names.join(","));
    for (n, row) in names.iter().zip(&m) {
        let vals: Vec<String> = row.iter().map(|v| format!("{v:.4}")).collect();
        let _ = writeln!(csv, "{n},{}", vals.join(","));
    }
    let csv_path = out.join("features_spearman.csv");
    std::fs::write(&csv_path, csv).with_context(|| format!("writing {}", csv_path.display()))?;
    // The picture keeps what a reader can read: the targets and the features most correlated with
    // α or β; the CSV holds the whole matrix.
    let (shown, sub) = trainer::analysis::most_correlated(&names, &m, HEATMAP_FEATURES);
    trainer::plots::heatmap(
        &out.join("features_spearman.png"),
        &format!(
            "Spearman rank correlation (training flights): the targets and the {} features most correlated with α or β",
            shown
                .len()
                .saturating_sub(names.len() - estimator_core::Feature::ALL.len())
        ),
        &shown,
        &sub,
    )?;
    let head = trainer::report::FeaturesHead {
        dataset: data.display().to_string(),
        preset: ds.preset.clone(),
        manifest_sha256: ds.manifest_sha256.clone(),
        command: command_line(),
        machine: machine(),
    };
    let md = trainer::report::features_markdown(
        &head,
        &names,
        &m,
        n_rows,
        &shap_section(&ds, out, shap)?,
    );
    let md_path = out.join("features.md");
    std::fs::write(&md_path, md).with_context(|| format!("writing {}", md_path.display()))?;
    eprintln!("wrote {}, features_spearman.csv/.png", md_path.display());
    Ok(())
}

/// SHAP of the compiled-in α and β cascades (integer path, `AngleNet::run`, exactly as deployed).
fn shap_section(ds: &Dataset, out: &Path, a: &ShapArgs) -> Result<String> {
    use trainer::analysis::{rng, sample_rows, shapley};
    let (Some([alpha, beta]), Some(prov)) = (
        estimator_core::model::shipped_networks(),
        estimator_core::model::SHIPPED_PROVENANCE,
    ) else {
        return Ok("## SHAP\n\nNot computed: this build has no compiled-in model (run `trainer train` first).\n".into());
    };
    let bg = sample_rows(ds, &[Role::Train, Role::Val], a.background);
    let xs = sample_rows(ds, &[Role::Test], a.explain);
    let prov = prov.lines().next().unwrap_or("");
    let mut charts = Vec::new();
    for (name, net) in [("alpha", alpha), ("beta", beta)] {
        let feats = net.features().to_vec();
        let f = |v: &estimator_core::FeatureValues| net.run(v).1 as f64 / 1000.0;
        let mut r = rng(a.seed);
        let pb = hil_sim::progress::bar(xs.len() as u64, "rows");
        pb.set_prefix(format!("SHAP {name}"));
        let mut sum = vec![0.0; feats.len()];
        for x in &xs {
            let phi = shapley(&f, &feats, x, &bg, a.permutations, &mut r);
            for (s, p) in sum.iter_mut().zip(&phi) {
                *s += p.abs();
            }
            pb.inc(1);
        }
        pb.finish_and_clear();
        let items: Vec<(String, f64)> = feats
            .iter()
            .zip(&sum)
            .map(|(f, s)| (f.name().to_string(), s / xs.len().max(1) as f64))
            .collect();
        let png = format!("features_shap_{name}.png");
        trainer::plots::bars(
            &out.join(&png),
            &format!("{name}: mean |SHAP| (deg), compiled-in int8 model"),
            "mean |SHAP| (deg)",
            &items,
        )?;
        charts.push(trainer::report::ShapChart {
            name: name.to_string(),
            items,
            png,
        });
    }
    Ok(trainer::report::shap_markdown(
        prov,
        xs.len(),
        bg.len(),
        a.permutations,
        a.seed,
        &charts,
    ))
}

fn cmd_bench(
    data: &Path,
    epochs: usize,
    batch: usize,
    replicas: Option<usize>,
    out: &Path,
) -> Result<()> {
    use trainer::model::{Cascade, train};
    use trainer::report::BenchEpoch;
    let ds = load(data, 0.15)?;
    let (train_m, val_m) = trainer::bench::alpha_matrices(&ds, &FeatureSet::parse("table1")?);
    let n_in = train_m.n_in;
    let cfg = TrainConfig {
        epochs,
        batch,
        lr: 1e-3,
        seed: 1,
        label: "alpha paper cascade".into(),
        progress: true,
        loss: Loss::Mse,
        replicas,
        bars: None,
    };
    let (_, curves) = train(
        |d| Cascade::new(n_in, Size::Paper.hidden(Angle::Alpha), d),
        &cfg,
        &train_m,
        &val_m,
    );
    let mean = curves.mean_after_warmup();
    let rows = train_m.rows();
    let v = BenchEpoch {
        batch,
        best_epoch: curves.best_epoch + 1,
        best_val_loss: curves
            .val
            .get(curves.best_epoch)
            .map_or(f64::NAN, |v| v[0] + v[1]),
        time_to_best_s: curves.epoch_s.iter().take(curves.best_epoch + 1).sum(),
        replicas: curves.replicas,
        command: command_line(),
        dataset: data.display().to_string(),
        first_epoch_s: curves.epoch_s[0],
        epoch_s: curves.epoch_s,
        epochs,
        machine: machine(),
        mean_epoch_s: mean,
        n_in,
        per_epoch_288k_s: mean * PAPER_TRAIN_ROWS as f64 / rows.max(1) as f64,
        train_rows: rows,
        val_rows: val_m.rows(),
    };
    println!(
        "paper α cascade ({n_in}-512-256-128-64-32-1 ×2), {rows} train rows, batch {batch}: \
         {mean:.2} s/epoch (epochs 2..{epochs}; first {:.2} s) → ≈{:.1} s/epoch at 288 000 rows",
        v.first_epoch_s, v.per_epoch_288k_s
    );
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let path = out.join("bench_epoch.json");
    std::fs::write(&path, serde_json::to_string_pretty(&v)?)
        .with_context(|| format!("writing {}", path.display()))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

struct BenchTrainOpts<'a> {
    epochs: usize,
    seeds: Vec<u64>,
    batch: usize,
    threads: usize,
    replicas: Option<usize>,
    cases: &'a [String],
    json: bool,
}

fn cmd_bench_train(
    data: &Path,
    o: &BenchTrainOpts,
    torch: &trainer::bench::Torch,
    out: &Path,
) -> Result<()> {
    use trainer::bench::{CASES, CaseSeeds, markdown, run_case};
    if o.seeds.len() > 20 {
        bail!("--seeds: at most 20 seeds (got {})", o.seeds.len());
    }
    let exchange = &out.join("exchange");
    rayon::ThreadPoolBuilder::new()
        .num_threads(o.threads)
        .build_global()
        .context("sizing rayon's thread pool (set --threads before anything else runs)")?;
    let cases: Vec<_> = if o.cases.is_empty() {
        CASES.to_vec()
    } else {
        o.cases
            .iter()
            .map(|n| {
                CASES
                    .iter()
                    .find(|c| c.name == n)
                    .copied()
                    .with_context(|| {
                        let known: Vec<_> = CASES.iter().map(|c| c.name).collect();
                        format!("unknown case `{n}` (known: {})", known.join(", "))
                    })
            })
            .collect::<Result<_>>()?
    };
    // The PyTorch side can start, before anything is trained or written to the exchange.
    torch.check()?;
    let ds = load(data, 0.15)?;
    let mut results = Vec::new();
    let seeds = o.seeds.clone();
    for case in &cases {
        ds.require(case.suite)?;
        let mut runs = Vec::new();
        for &seed in &seeds {
            let cfg = TrainConfig {
                epochs: o.epochs,
                batch: o.batch,
                lr: 1e-3,
                seed,
                label: format!("burn {} seed {seed}", case.name),
                progress: !o.json,
                loss: Loss::Mse, // run_case trains with the case's own loss
                replicas: o.replicas,
                bars: None,
            };
            let r = run_case(&ds, case, &cfg, torch, exchange)?;
            eprintln!("seed {seed}: {}", r.summary());
            runs.push(r);
        }
        let c = CaseSeeds::new(runs, seeds.clone()).context("no seeds were run")?;
        eprintln!("{}", c.summary());
        results.push(c);
    }
    let first = results.first();
    let summary = serde_json::json!({
        "command": command_line(),
        "machine": machine(),
        "dataset": data.display().to_string(),
        "threads": o.threads,
        "seeds": seeds,
        "cases": results,
        "ratio": first.map(|c| c.ratio),
        "burn_s_per_epoch": first.map(|c| c.burn_s_per_epoch),
        "torch_s_per_epoch": first.map(|c| c.torch_s_per_epoch),
        "burn_val_loss": first.map(|c| c.burn_val_loss),
        "torch_val_loss": first.map(|c| c.torch_val_loss),
        "val_loss_rel": first.map(|c| c.val_loss_rel),
    });
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let md_path = out.join("training-speed.md");
    std::fs::write(&md_path, markdown(&results, &command_line(), &machine()))
        .with_context(|| format!("writing {}", md_path.display()))?;
    let json_path = out.join("training-speed.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&summary)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    if o.json {
        println!("{summary}");
    } else {
        eprintln!("wrote {} and {}", md_path.display(), json_path.display());
    }
    Ok(())
}

fn main() -> std::process::ExitCode {
    hil_sim::error_text::main(run)
}

/// `path`, else the build's aircraft's committed file `estimator-core/PATTERN` (`{}` = its name).
fn committed(path: &Option<PathBuf>, pattern: &str) -> PathBuf {
    path.clone().unwrap_or_else(|| {
        PathBuf::from("estimator-core")
            .join(pattern.replace("{}", estimator_core::aircraft::AIRCRAFT.name))
    })
}

/// Where an export writes the weights and the test vectors: the given files, else the build's
/// aircraft's committed ones.
fn export_paths(
    weights_out: &Option<PathBuf>,
    vectors_out: &Option<PathBuf>,
) -> (PathBuf, PathBuf) {
    (
        committed(weights_out, "src/model/{}/weights.rs"),
        committed(vectors_out, "tests/vectors/{}.txt"),
    )
}

fn run() -> Result<()> {
    let cli = Cli::parse();
    check_outputs(&cli.cmd)?;
    match &cli.cmd {
        Cmd::Train {
            weights_out,
            vectors_out,
            export: false,
            ..
        } if weights_out.is_some() || vectors_out.is_some() => bail!(
            "--weights-out and --vectors-out say where --export writes: pass --export too, or drop them"
        ),
        Cmd::Train {
            args,
            out,
            weights_out,
            vectors_out,
            export,
        } => {
            let (w, v) = export_paths(weights_out, vectors_out);
            cmd_train(args, out, &w, &v, *export)
        }
        Cmd::Export {
            model,
            data,
            weights_out,
            vectors_out,
        } => {
            let (w, v) = export_paths(weights_out, vectors_out);
            cmd_export(model, data, &w, &v)
        }
        Cmd::Combine { alpha, beta, out } => cmd_combine(alpha, beta, out),
        Cmd::Revector { weights, vectors } => {
            let (w, v) = export_paths(weights, vectors);
            cmd_revector(&w, &v)
        }
        Cmd::Eval {
            model,
            uncertain_hold: Some(_),
            ..
        } if !model.is_empty() => bail!(
            "--uncertain-hold sets a flag of the compiled-in estimator; --model scores networks alone, which carry no flags: drop one of the two"
        ),
        Cmd::Eval {
            data,
            model,
            split,
            suite,
            uncertain_hold: None,
            json,
        } if !model.is_empty() => cmd_eval_model(data, model, split, suite.as_deref(), *json),
        Cmd::Eval {
            data,
            model: _,
            split,
            suite,
            uncertain_hold,
            json,
        } => cmd_eval(
            data,
            split,
            suite.as_deref(),
            uncertain_hold.unwrap_or(estimator_core::UNCERTAIN_HOLD_FRAMES),
            *json,
        ),
        Cmd::EvalFilter {
            data,
            split,
            tune,
            json,
            frames,
        } => cmd_eval_filter(data, split, tune, *json, frames.as_deref()),
        Cmd::FitSigma {
            data,
            every,
            out,
            rows,
            json,
        } => cmd_fit_sigma(
            data,
            *every,
            &committed(out, "src/model/{}/sigma.rs"),
            rows.as_deref(),
            *json,
        ),
        Cmd::Calibrate {
            flight_test,
            model_flight_test,
            moment_flight_test,
            first_calibration,
            out,
            json,
        } => cmd_calibrate(
            flight_test,
            model_flight_test,
            moment_flight_test,
            first_calibration.as_deref(),
            out,
            *json,
        ),
        Cmd::Finetune {
            model,
            flight_test,
            out,
            epochs,
            lr,
            batch,
            seed,
            loss,
            replay,
            tune,
            json,
        } => cmd_finetune(
            model,
            flight_test,
            out,
            replay.as_deref(),
            *tune,
            TrainConfig {
                epochs: *epochs,
                batch: *batch,
                lr: *lr,
                seed: *seed,
                label: String::new(),
                progress: !*json,
                loss: *loss,
                replicas: None,
                bars: None,
            },
            *json,
        ),
        Cmd::Ood { data, out, json } => cmd_ood(data, out, *json),
        Cmd::Bars { spec, out } => cmd_bars(spec, out),
        Cmd::Lines { spec, out } => cmd_lines(spec, out),
        Cmd::Sweep { grid, action } => cmd_sweep(grid, action),
        Cmd::Report(r) => cmd_report(r),
        Cmd::Features {
            data,
            out,
            rows,
            seed,
            explain,
            background,
            permutations,
        } => cmd_features(
            data,
            out,
            *rows,
            &ShapArgs {
                seed: *seed,
                explain: *explain,
                background: *background,
                permutations: *permutations,
            },
        ),
        Cmd::BenchEpoch {
            data,
            epochs,
            batch,
            out,
            replicas,
        } => cmd_bench(data, *epochs, *batch, replicas.get(), out),
        Cmd::Baselines { args, gb_rows } => cmd_baselines(args, *gb_rows),
        Cmd::BenchTrain {
            data,
            epochs,
            batch,
            threads,
            seeds,
            case,
            python,
            torch_script,
            out,
            json,
            replicas,
        } => cmd_bench_train(
            data,
            &BenchTrainOpts {
                epochs: *epochs,
                seeds: seeds.0.clone(),
                batch: *batch,
                threads: *threads,
                replicas: replicas.get(),
                cases: case,
                json: *json,
            },
            &trainer::bench::Torch {
                python,
                script: torch_script,
                threads: *threads,
            },
            out,
        ),
    }
}

#[cfg(test)]
mod tests {
    /// scripts/build-estimator refuses an unknown `--config` before it builds: its list is exactly
    /// the network sizes `trainer train --config` takes.
    #[test]
    fn build_estimator_lists_exactly_the_network_sizes() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let text = std::fs::read_to_string(root.join("scripts/build-estimator"))
            .expect("reading scripts/build-estimator");
        let line = text
            .lines()
            .find_map(|l| l.strip_prefix("configs=\""))
            .expect("scripts/build-estimator has a configs=\"...\" line");
        let listed: Vec<&str> = line.trim_end_matches('"').split_whitespace().collect();
        let sizes: Vec<&str> = trainer::pipeline::Size::ALL
            .iter()
            .map(|z| z.name())
            .collect();
        assert_eq!(listed, sizes);
    }

    /// A `--tune` value that is not finite, out of its key's range or not a whole number where one
    /// is meant is refused with the key's range; values in range are taken as given.
    #[test]
    fn a_tune_value_outside_its_range_is_refused() {
        for (tune, says) in [
            ("gust_sigma=nan", "gust_sigma must be 0 or more"),
            ("gust_sigma=inf", "gust_sigma must be 0 or more"),
            ("gust_sigma=1e39", "gust_sigma must be 0 or more"),
            ("gate=-1", "gate must be more than 0"),
            ("gust_tau_s=0", "gust_tau_s must be more than 0"),
            ("accel_sigma_y=0", "accel_sigma_y must be more than 0"),
            ("lift_scale_psd=-1e-6", "lift_scale_psd must be 0 or more"),
            (
                "gear_norm=1.5",
                "gear_norm must be between 0 (up) and 1 (down)",
            ),
            (
                "subsamples=1.7",
                "subsamples must be 0 (off), 1 (latest) or 2 (period mean)",
            ),
            (
                "subsamples=3",
                "subsamples must be 0 (off), 1 (latest) or 2 (period mean)",
            ),
            ("r_adapt_tau_s=-2", "r_adapt_tau_s must be 0 or more"),
        ] {
            let e = super::filter_config(tune).unwrap_err().to_string();
            assert!(
                e.starts_with("--tune: ") && e.ends_with(says),
                "{tune}: {e}"
            );
        }
        let e = super::filter_config("bogus=-1").unwrap_err().to_string();
        assert!(e.contains("unknown key `bogus`"), "{e}");
        let c = super::filter_config("subsamples=2,gate=30,accel_delay_s=0,gear_norm=0").unwrap();
        assert_eq!(c.subsamples, estimator_core::filter::SubsampleUse::Mean);
        assert_eq!((c.gate, c.accel_delay_s, c.gear_norm), (30.0, 0.0, 0.0));
    }

    #[test]
    fn bench_epochs_are_at_least_two_in_one_message() {
        for bad in ["0", "1"] {
            let e = super::bench_epochs(bad).unwrap_err();
            assert_eq!(
                e,
                "must be at least 2 (the first epoch is warm-up and is not averaged)"
            );
        }
        assert_eq!(super::bench_epochs("2"), Ok(2));
    }

    /// An output that cannot be written is refused before any work, saying why; one that can is
    /// taken, and nothing is created by the check.
    #[test]
    fn outputs_are_checked_before_any_work() {
        let dir = std::env::temp_dir().join(format!("trainer-outputs-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("afile");
        std::fs::write(&file, "x").unwrap();
        let err = |r: anyhow::Result<()>| r.unwrap_err().to_string();
        assert_eq!(
            err(super::check_out_dir("--out", &file)),
            format!(
                "--out {} is a file, not a directory: give a directory",
                file.display()
            )
        );
        let under = file.join("x");
        assert!(err(super::check_out_dir("--out", &under)).contains("is a file, so no directory"));
        assert!(
            err(super::check_out_dir(
                "--out",
                std::path::Path::new("/dev/null/x")
            ))
            .contains("/dev/null is a file")
        );
        super::check_out_dir("--out", &dir.join("new/deeper")).unwrap();
        super::check_out_dir("--out", &dir).unwrap();
        assert!(!dir.join("new").exists());

        assert!(err(super::check_out_file("--out", &dir, false)).contains("is a directory"));
        assert!(
            err(super::check_out_file(
                "--frames",
                &dir.join("none/f.csv"),
                false
            ))
            .contains("the directory")
        );
        assert!(
            err(super::check_out_file("--weights-out", &under, true)).contains("afile is a file")
        );
        super::check_out_file("--weights-out", &dir.join("new/w.rs"), true).unwrap();
        super::check_out_file("--frames", &dir.join("f.csv"), false).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Every `trainer` command line in README.md and docs/ parses against this CLI: its flags exist
    /// and its values parse (a line may leave out required flags, as prose does).
    #[test]
    fn every_trainer_command_in_the_docs_parses() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let (n, bad) =
            hil_sim::docs_cli::unparsed::<super::Cli>(&root, "trainer").expect("reading the docs");
        assert!(n >= 10, "only {n} trainer commands found");
        assert!(bad.is_empty(), "{}", bad.join("\n"));
    }
}
