//! `trainer bench-train`: burn and PyTorch train the same cascade side by side, in one run, once per
//! seed.
//!
//! Both sides get the same prepared design matrices, the same initial weights (burn's seeded
//! initialisation, handed to PyTorch), the same row order in every epoch, the same optimiser
//! (Adam with the same constants and the same per-epoch learning rates), the same batch size, the
//! same per-epoch validation pass and the same thread count. Each epoch's time covers the batches,
//! the optimiser steps, the per-batch loss read-out and the validation pass. The two run in
//! lockstep, epoch by epoch, so both meet the machine in the same state. The PyTorch side is
//! `scripts/bench/torch_train.py`, run in the benchmark venv (`scripts/bench-train` makes it).
use crate::data::{Dataset, Role};
use crate::features::FeatureSet;
use crate::model::{
    ADAM_BETA_1, ADAM_BETA_2, ADAM_EPSILON, Cascade, Curves, Loss, Matrix, Net, Shuffle,
    TrainConfig, init_model, lr_at, train_with,
};
use crate::pipeline::Size;
use crate::prep::{Angle, Prep};
use crate::{Error, Result};
use estimator_core::Suite;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One benchmarked configuration.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    pub name: &'static str,
    pub what: &'static str,
    pub features: &'static str,
    pub suite: Suite,
    pub size: Size,
    /// The training loss, on both sides.
    pub loss: Loss,
}

/// The paper-size α cascade on the paper's inputs, and the shipped α cascade's sizes and loss on
/// the `egi-hybrid-fast` inputs.
pub const CASES: [Case; 2] = [
    Case {
        name: "paper-alpha",
        what: "paper-size α cascade (512-256-128-64-32 per part), Table 1 inputs",
        features: "table1",
        suite: Suite::Table1,
        size: Size::Paper,
        loss: Loss::Mse,
    },
    Case {
        name: "shipped-alpha",
        what: "the shipped α cascade's sizes (64-32-16 per part) and L1 loss on the \
               egi-hybrid-fast inputs (the shipped networks read the egi120 set's 75)",
        features: "egi-hybrid-fast",
        suite: Suite::Egi,
        size: Size::Medium,
        loss: Loss::L1,
    },
];

/// One framework's run of one case.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Side {
    /// Framework and version.
    pub framework: String,
    pub threads: usize,
    pub epoch_s: Vec<f64>,
    /// Mean of epochs 2..N (the first one carries warm-up).
    pub mean_epoch_s: f64,
    /// Per-epoch mean training-batch losses `[intermediate, angle]`.
    pub train: Vec<[f64; 2]>,
    /// Per-epoch validation losses `[intermediate, angle]`.
    pub val: Vec<[f64; 2]>,
}

impl Side {
    fn new(framework: String, threads: usize, c: Curves) -> Side {
        Side {
            framework,
            threads,
            mean_epoch_s: c.mean_after_warmup(),
            epoch_s: c.epoch_s,
            train: c.train,
            val: c.val,
        }
    }
    /// Validation loss (both heads) after epoch `e` (0-based).
    pub fn val_at(&self, e: usize) -> f64 {
        self.val.get(e).map_or(f64::NAN, |v| v[0] + v[1])
    }
    /// Validation loss (both heads) after the last epoch.
    pub fn final_val(&self) -> f64 {
        self.val.last().map_or(f64::NAN, |v| v[0] + v[1])
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct CaseResult {
    pub name: String,
    pub what: String,
    pub n_in: usize,
    pub hidden: Vec<usize>,
    pub train_rows: usize,
    pub val_rows: usize,
    pub batch: usize,
    pub epochs: usize,
    /// Replicas burn split each batch over (`TrainConfig::replicas`; PyTorch: one pass).
    pub replicas: usize,
    pub burn: Side,
    pub torch: Side,
    /// burn's mean epoch time over PyTorch's (below 1: burn is faster).
    pub ratio: f64,
    /// burn's final validation loss relative to PyTorch's, minus 1 (negative: burn's is lower).
    pub val_loss_rel: f64,
}

impl CaseResult {
    /// One line: both epoch times, the ratio and both final validation losses.
    pub fn summary(&self) -> String {
        format!(
            "{}: burn {:.2} s/epoch, PyTorch {:.2} s/epoch, ratio {:.2}; val loss {:.5} vs {:.5} ({:+.1} %)",
            self.name,
            self.burn.mean_epoch_s,
            self.torch.mean_epoch_s,
            self.ratio,
            self.burn.final_val(),
            self.torch.final_val(),
            100.0 * self.val_loss_rel
        )
    }
}

/// One case run once per seed, each seed a full side-by-side run (its own initial weights and row
/// order on both sides). A single epoch's validation loss moves by up to 25 % from one epoch to the
/// next on both sides, and the two sides' rounding drifts apart, so one seed's loss comparison is
/// mostly that noise; the mean over seeds is the framework's.
#[derive(Debug, Clone, Serialize)]
pub struct CaseSeeds {
    pub name: String,
    pub seeds: Vec<u64>,
    /// Mean over seeds of each side's mean epoch time.
    pub burn_s_per_epoch: f64,
    pub torch_s_per_epoch: f64,
    /// `burn_s_per_epoch / torch_s_per_epoch` (below 1: burn is faster).
    pub ratio: f64,
    /// Mean over seeds of each side's validation loss after the last epoch.
    pub burn_val_loss: f64,
    pub torch_val_loss: f64,
    /// `burn_val_loss / torch_val_loss - 1` (negative: burn's is lower).
    pub val_loss_rel: f64,
    /// The smallest and largest single-seed `val_loss_rel`.
    pub val_loss_rel_range: [f64; 2],
    pub runs: Vec<CaseResult>,
}

impl CaseSeeds {
    /// Aggregates the runs of one case, `runs[i]` made with `seeds[i]`; `None` for no runs, or
    /// runs and seeds of different lengths or cases. A seed whose loss is NaN (diverged) makes the
    /// means and the range NaN: it is not dropped.
    pub fn new(runs: Vec<CaseResult>, seeds: Vec<u64>) -> Option<CaseSeeds> {
        let first = runs.first()?;
        if runs.len() != seeds.len() || runs.iter().any(|r| r.name != first.name) {
            return None;
        }
        let n = runs.len() as f64;
        let mean = |f: &dyn Fn(&CaseResult) -> f64| runs.iter().map(f).sum::<f64>() / n;
        let burn_s = mean(&|r| r.burn.mean_epoch_s);
        let torch_s = mean(&|r| r.torch.mean_epoch_s);
        let burn_v = mean(&|r| r.burn.final_val());
        let torch_v = mean(&|r| r.torch.final_val());
        let rel: Vec<f64> = runs.iter().map(|r| r.val_loss_rel).collect();
        let range = if rel.iter().any(|v| v.is_nan()) {
            [f64::NAN; 2]
        } else {
            [
                rel.iter().copied().fold(f64::INFINITY, f64::min),
                rel.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ]
        };
        Some(CaseSeeds {
            name: first.name.clone(),
            seeds,
            burn_s_per_epoch: burn_s,
            torch_s_per_epoch: torch_s,
            ratio: burn_s / torch_s,
            burn_val_loss: burn_v,
            torch_val_loss: torch_v,
            val_loss_rel: burn_v / torch_v - 1.0,
            val_loss_rel_range: range,
            runs,
        })
    }

    /// One line: both mean epoch times, the ratio and both mean final validation losses.
    pub fn summary(&self) -> String {
        format!(
            "{} over {} seed(s): burn {:.2} s/epoch, PyTorch {:.2} s/epoch, ratio {:.2}; mean val \
             loss {:.5} vs {:.5} ({:+.1} %; single seeds {:+.1} to {:+.1} %)",
            self.name,
            self.seeds.len(),
            self.burn_s_per_epoch,
            self.torch_s_per_epoch,
            self.ratio,
            self.burn_val_loss,
            self.torch_val_loss,
            100.0 * self.val_loss_rel,
            100.0 * self.val_loss_rel_range[0],
            100.0 * self.val_loss_rel_range[1],
        )
    }
}

/// The α design matrices (training, validation) of `fs` on `ds`, as `train_angle` prepares them.
pub fn alpha_matrices(ds: &Dataset, fs: &FeatureSet) -> (Matrix, Matrix) {
    let tr: Vec<_> = ds.flights(Role::Train).collect();
    let va: Vec<_> = ds.flights(Role::Val).collect();
    let prep = Prep::fit(Angle::Alpha, &fs.alpha, &tr);
    (prep.matrix(&tr), prep.matrix(&va))
}

/// What the benchmark needs from outside: the PyTorch interpreter and script.
pub struct Torch<'a> {
    pub python: &'a Path,
    pub script: &'a Path,
    pub threads: usize,
}

impl Torch<'_> {
    /// The PyTorch side can run: its script is a file and the interpreter starts and imports
    /// torch. Checked before anything is trained or written to the exchange directory.
    pub fn check(&self) -> Result<()> {
        let status = std::process::Command::new(self.python)
            .args(["-c", "import torch"])
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .status();
        let why = match status {
            Ok(s) if s.success() => None,
            Ok(s) => Some(format!(
                "cannot import torch ({s}; its error is printed above)"
            )),
            Err(e) => Some(format!("cannot be started ({e})")),
        };
        if let Some(why) = why {
            return Err(Error::Torch(format!(
                "--python {} {why}; run scripts/bench-train, which makes the benchmark venv",
                self.python.display()
            )));
        }
        if !self.script.is_file() {
            return Err(Error::Torch(format!(
                "--torch-script {} is not a file: give the path of scripts/bench/torch_train.py \
                 (the default is relative to the repository's root)",
                self.script.display()
            )));
        }
        Ok(())
    }
}

fn write_f32(path: &Path, v: impl IntoIterator<Item = f32>) -> Result<()> {
    let bytes: Vec<u8> = v.into_iter().flat_map(f32::to_le_bytes).collect();
    std::fs::write(path, bytes).map_err(crate::error::io("write", path))
}

#[derive(Serialize)]
struct Meta<'a> {
    n_in: usize,
    hidden: &'a [usize],
    train_rows: usize,
    val_rows: usize,
    batch: usize,
    lr: Vec<f64>,
    beta_1: f32,
    beta_2: f32,
    epsilon: f32,
    /// `mse` or `l1` (`Loss::name`).
    loss: &'static str,
}

/// Writes what PyTorch needs to train exactly the run burn makes.
fn write_exchange(
    dir: &Path,
    init: &Cascade,
    hidden: &[usize],
    cfg: &TrainConfig,
    tr: &Matrix,
    va: &Matrix,
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(crate::error::io("create", dir))?;
    for (name, m) in [("train", tr), ("val", va)] {
        write_f32(&dir.join(format!("x_{name}.f32")), m.x.iter().copied())?;
        write_f32(&dir.join(format!("ym_{name}.f32")), m.ym.iter().copied())?;
        write_f32(&dir.join(format!("yo_{name}.f32")), m.yo.iter().copied())?;
    }
    let weights = init
        .layers()
        .into_iter()
        .flat_map(|l| l.weights.into_iter().flatten().chain(l.bias));
    write_f32(&dir.join("init.f32"), weights)?;
    let mut shuffle = Shuffle::new(tr.rows(), cfg.seed);
    let mut order = Vec::with_capacity(cfg.epochs * tr.rows() * 4);
    for _ in 0..cfg.epochs {
        for &i in shuffle.next_epoch() {
            let i = u32::try_from(i).map_err(|_| Error::Numeric("more than 2^32 rows".into()))?;
            order.extend_from_slice(&i.to_le_bytes());
        }
    }
    let p = dir.join("order.u32");
    std::fs::write(&p, order).map_err(crate::error::io("write", &p))?;
    let meta = Meta {
        n_in: tr.n_in,
        hidden,
        train_rows: tr.rows(),
        val_rows: va.rows(),
        batch: cfg.batch,
        lr: (0..cfg.epochs)
            .map(|e| lr_at(cfg.lr, e, cfg.epochs))
            .collect(),
        beta_1: ADAM_BETA_1,
        beta_2: ADAM_BETA_2,
        epsilon: ADAM_EPSILON,
        loss: cfg.loss.name(),
    };
    let p = dir.join("meta.json");
    let text = serde_json::to_string(&meta).map_err(|e| Error::Torch(e.to_string()))?;
    std::fs::write(&p, text).map_err(crate::error::io("write", &p))
}

#[derive(Deserialize)]
struct TorchHello {
    torch: String,
    threads: usize,
}

#[derive(Deserialize)]
struct TorchEpoch {
    epoch_s: f64,
    train: [f64; 2],
    val: [f64; 2],
}

/// The PyTorch process, one epoch per request: it trains epoch `k` when burn has finished its own,
/// so both frameworks meet the machine in the same state (the host's speed drifts by ±20 % over
/// minutes here; back-to-back whole runs would measure that drift).
struct TorchChild {
    child: std::process::Child,
    stdin: std::process::ChildStdin,
    lines: std::io::Lines<std::io::BufReader<std::process::ChildStdout>>,
    framework: String,
    threads: usize,
    curves: Curves,
}

impl TorchChild {
    fn start(t: &Torch, dir: &Path) -> Result<TorchChild> {
        use std::io::BufRead;
        use std::process::{Command, Stdio};
        let mut child = Command::new(t.python)
            .arg(t.script)
            .arg(dir)
            .arg("--threads")
            .arg(t.threads.to_string())
            .env("OMP_NUM_THREADS", t.threads.to_string())
            .env("MKL_NUM_THREADS", t.threads.to_string())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| {
                Error::Torch(format!(
                    "cannot start {} ({e}); run scripts/bench-train, which makes the benchmark venv",
                    t.python.display()
                ))
            })?;
        let (Some(stdin), Some(stdout)) = (child.stdin.take(), child.stdout.take()) else {
            return Err(Error::Torch("no pipes to the PyTorch process".into()));
        };
        let mut c = TorchChild {
            child,
            stdin,
            lines: std::io::BufReader::new(stdout).lines(),
            framework: String::new(),
            threads: 0,
            curves: Curves::default(),
        };
        let hello: TorchHello = c.read()?;
        c.framework = format!("PyTorch {}", hello.torch);
        c.threads = hello.threads;
        Ok(c)
    }

    fn read<T: serde::de::DeserializeOwned>(&mut self) -> Result<T> {
        let line = match self.lines.next() {
            Some(Ok(l)) => l,
            Some(Err(e)) => return Err(Error::Torch(format!("reading its answer: {e}"))),
            None => {
                let status = self.child.wait().map(|s| s.to_string()).unwrap_or_default();
                return Err(Error::Torch(format!(
                    "the PyTorch process ended ({status}); its error is printed above"
                )));
            }
        };
        serde_json::from_str(&line).map_err(|e| Error::Torch(format!("answer `{line}`: {e}")))
    }

    fn epoch(&mut self, k: usize) -> Result<()> {
        use std::io::Write;
        writeln!(self.stdin, "{k}")
            .and_then(|()| self.stdin.flush())
            .map_err(|e| Error::Torch(format!("asking for epoch {k}: {e}")))?;
        let e: TorchEpoch = self.read()?;
        self.curves.epoch_s.push(e.epoch_s);
        self.curves.train.push(e.train);
        self.curves.val.push(e.val);
        Ok(())
    }

    fn finish(mut self) -> Side {
        drop(self.stdin);
        let _ = self.child.wait();
        Side::new(self.framework, self.threads, self.curves)
    }
}

/// The burn version and kernels the trainer is built with.
pub const BURN: &str = if cfg!(feature = "avx512") {
    "burn 0.22.1 (flex backend, gemm AVX-512 kernels: feature avx512)"
} else {
    "burn 0.22.1 (flex backend, gemm AVX2/FMA kernels)"
};

/// Runs one case: burn first, then PyTorch on the exchange burn wrote, both with the case's loss
/// (whatever `cfg.loss` says).
pub fn run_case(
    ds: &Dataset,
    case: &Case,
    cfg: &TrainConfig,
    torch: &Torch,
    exchange: &Path,
) -> Result<CaseResult> {
    let cfg = &TrainConfig {
        loss: case.loss,
        ..cfg.clone()
    };
    let fs = FeatureSet::parse(case.features)?;
    fs.check_suite(case.suite)?;
    let (tm, vm) = alpha_matrices(ds, &fs);
    let n_in = tm.n_in;
    let hidden = case.size.hidden(Angle::Alpha);
    let make = |d: &burn::tensor::Device| Cascade::new(n_in, hidden, d);
    let dir: PathBuf = exchange.join(case.name);
    write_exchange(&dir, &init_model(make, cfg.seed), hidden, cfg, &tm, &vm)?;
    let mut torch = TorchChild::start(torch, &dir)?;
    let mut failed = None;
    let (_, curves) = train_with(make, cfg, &tm, &vm, |epoch| {
        if failed.is_none() {
            failed = torch.epoch(epoch).err();
        }
    });
    if let Some(e) = failed {
        return Err(e);
    }
    let replicas = curves.replicas;
    let framework = match replicas {
        1 => BURN.to_string(),
        r => format!("{BURN}, each batch split over {r} replicas"),
    };
    let burn = Side::new(framework, rayon::current_num_threads(), curves);
    let torch = torch.finish();
    Ok(CaseResult {
        name: case.name.into(),
        what: case.what.into(),
        n_in,
        hidden: hidden.to_vec(),
        train_rows: tm.rows(),
        val_rows: vm.rows(),
        batch: cfg.batch,
        epochs: cfg.epochs,
        replicas,
        ratio: burn.mean_epoch_s / torch.mean_epoch_s,
        val_loss_rel: burn.final_val() / torch.final_val() - 1.0,
        burn,
        torch,
    })
}

/// The benchmark's Markdown page.
pub fn markdown(results: &[CaseSeeds], command: &str, machine: &str) -> String {
    let mut s = String::from(
        "# Training speed: burn against PyTorch, side by side\n\n\
         Written by `trainer bench-train` (run it through `scripts/bench-train`, which makes the \
         PyTorch venv and the dataset). Both frameworks train the same cascade from the same initial \
         weights on the same batches in the same order, with Adam (same constants, same per-epoch \
         learning rates), the same validation pass each epoch and the same thread count. An epoch's \
         time is the mean of epochs 2..N (the first carries warm-up). Each seed is a full \
         side-by-side run with its own initial weights and row order; the first table gives the \
         means over the seeds, the validation losses after the last epoch.\n\n",
    );
    s += "How it is made fair, where burn's time goes and the backends offered: \
          [docs/training-speed.md](../training-speed.md).\n\n";
    s += &format!("Command: `{command}`\n\nMachine: {machine}\n\n");
    s += "| case | rows | epochs | seeds | burn s/epoch | PyTorch s/epoch | ratio burn/PyTorch | val loss burn | val loss PyTorch | difference | single seeds |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    for c in results {
        let Some(r) = c.runs.first() else { continue };
        s += &format!(
            "| {} | {} | {} | {} | {:.2} | {:.2} | **{:.2}** | {:.5} | {:.5} | **{:+.1} %** | {:+.1} to {:+.1} % |\n",
            c.name,
            r.train_rows,
            r.epochs,
            c.seeds.len(),
            c.burn_s_per_epoch,
            c.torch_s_per_epoch,
            c.ratio,
            c.burn_val_loss,
            c.torch_val_loss,
            100.0 * c.val_loss_rel,
            100.0 * c.val_loss_rel_range[0],
            100.0 * c.val_loss_rel_range[1],
        );
    }
    s += "\n";
    for c in results {
        let Some(r) = c.runs.first() else { continue };
        s += &format!(
            "**{}**: {}; {} inputs, batch {}; {} ({} threads) against {} ({} threads).\n\n",
            c.name,
            r.what,
            r.n_in,
            r.batch,
            r.burn.framework,
            r.burn.threads,
            r.torch.framework,
            r.torch.threads
        );
        s += "| seed | burn s/epoch | PyTorch s/epoch | ratio | burn val loss | PyTorch val loss | difference |\n|---|---|---|---|---|---|---|\n";
        for (seed, r) in c.seeds.iter().zip(&c.runs) {
            s += &format!(
                "| {seed} | {:.2} | {:.2} | {:.2} | {:.5} | {:.5} | {:+.1} % |\n",
                r.burn.mean_epoch_s,
                r.torch.mean_epoch_s,
                r.ratio,
                r.burn.final_val(),
                r.torch.final_val(),
                100.0 * r.val_loss_rel
            );
        }
        s += "\nPer epoch:\n\n| seed | epoch | burn s | PyTorch s | burn val loss | PyTorch val loss |\n|---|---|---|---|---|---|\n";
        for (seed, r) in c.seeds.iter().zip(&c.runs) {
            for (e, (b, t)) in r.burn.epoch_s.iter().zip(&r.torch.epoch_s).enumerate() {
                let (bv, tv) = (r.burn.val_at(e), r.torch.val_at(e));
                s += &format!(
                    "| {seed} | {} | {b:.2} | {t:.2} | {bv:.5} | {tv:.5} |\n",
                    e + 1
                );
            }
        }
        s += "\n";
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_u32(p: &Path) -> Vec<u32> {
        std::fs::read(p)
            .unwrap()
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
            .collect()
    }

    fn run(burn_s: f64, torch_s: f64, burn_val: f64, torch_val: f64) -> CaseResult {
        let side = |s: f64, v: f64| Side {
            framework: String::new(),
            threads: 2,
            epoch_s: vec![9.0, s],
            mean_epoch_s: s,
            train: vec![[0.0; 2]; 2],
            val: vec![[1.0, 1.0], [v / 4.0, 3.0 * v / 4.0]],
        };
        let (burn, torch) = (side(burn_s, burn_val), side(torch_s, torch_val));
        CaseResult {
            name: "c".into(),
            what: String::new(),
            n_in: 1,
            hidden: vec![],
            train_rows: 1,
            val_rows: 1,
            batch: 1,
            epochs: 2,
            replicas: 1,
            ratio: burn_s / torch_s,
            val_loss_rel: burn_val / torch_val - 1.0,
            burn,
            torch,
        }
    }

    /// The seeds' means are compared, not the mean of the per-seed ratios: two seeds at -10 % and
    /// +10 % around different losses are not a tie.
    #[test]
    fn seeds_compare_their_means() {
        let c = CaseSeeds::new(
            vec![run(6.0, 8.0, 0.09, 0.10), run(8.0, 16.0, 0.22, 0.20)],
            vec![1, 2],
        )
        .unwrap();
        assert_eq!(c.burn_s_per_epoch, 7.0);
        assert_eq!(c.torch_s_per_epoch, 12.0);
        // 7/12, not the mean of the per-seed ratios (0.75 + 0.5) / 2.
        assert_eq!(c.ratio, 7.0 / 12.0);
        assert!((c.burn_val_loss - 0.155).abs() < 1e-12);
        assert!((c.torch_val_loss - 0.15).abs() < 1e-12);
        assert!((c.val_loss_rel - (0.155 / 0.15 - 1.0)).abs() < 1e-12);
        assert!((c.val_loss_rel_range[0] + 0.1).abs() < 1e-12);
        assert!((c.val_loss_rel_range[1] - 0.1).abs() < 1e-12);
        assert!(CaseSeeds::new(vec![], vec![]).is_none());
        assert!(CaseSeeds::new(vec![run(1.0, 1.0, 1.0, 1.0)], vec![1, 2]).is_none());
        let nan = CaseSeeds::new(
            vec![run(1.0, 1.0, 1.0, 1.0), run(1.0, 1.0, f64::NAN, 1.0)],
            vec![1, 2],
        )
        .unwrap();
        assert!(nan.burn_val_loss.is_nan() && nan.val_loss_rel.is_nan());
        assert!(nan.val_loss_rel_range.iter().all(|v| v.is_nan()));
        let page = markdown(&[c], "cmd", "machine");
        for row in [
            // the means
            "| c | 1 | 2 | 2 | 7.00 | 12.00 | **0.58** | 0.15500 | 0.15000 | **+3.3 %** | -10.0 to +10.0 % |",
            // seed 2's run
            "| 2 | 8.00 | 16.00 | 0.50 | 0.22000 | 0.20000 | +10.0 % |",
            // seed 2's second epoch
            "| 2 | 2 | 8.00 | 16.00 | 0.22000 | 0.20000 |",
        ] {
            assert!(page.contains(row), "{row} missing from\n{page}");
        }
    }

    /// What PyTorch reads is what burn trains: every parameter once, in the cascade's layer order;
    /// each epoch's row order a permutation, the one `train` draws; the per-epoch learning rates.
    #[test]
    fn exchange_holds_the_run_burn_makes() {
        let (n_in, hidden, rows) = (4, [6usize, 3], 10);
        let m = |r: usize| Matrix {
            x: (0..r * n_in).map(|i| i as f32).collect(),
            ym: (0..r).map(|i| i as f32).collect(),
            yo: (0..r).map(|i| -(i as f32)).collect(),
            n_in,
        };
        let (tr, va) = (m(rows), m(3));
        let cfg = TrainConfig {
            epochs: 3,
            batch: 4,
            lr: 1e-3,
            seed: 5,
            label: String::new(),
            progress: false,
            loss: Loss::Mse,
            replicas: None,
            bars: None,
        };
        let dir = std::env::temp_dir().join(format!("bench-exchange-{}", std::process::id()));
        let model = init_model(|d| Cascade::new(n_in, &hidden, d), cfg.seed);
        write_exchange(&dir, &model, &hidden, &cfg, &tr, &va).unwrap();

        let params = |n: usize| n * 6 + 6 + 6 * 3 + 3 + 3 + 1;
        let init = std::fs::read(dir.join("init.f32")).unwrap();
        assert_eq!(init.len(), 4 * (params(n_in) + params(n_in + 1)));
        let first: Vec<f32> = model.layers()[0].weights[0].clone();
        let got: Vec<f32> = init[..4 * n_in]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(got, first, "layer 0, output 0's weights lead the file");

        let order = read_u32(&dir.join("order.u32"));
        assert_eq!(order.len(), cfg.epochs * rows);
        let mut shuffle = Shuffle::new(rows, cfg.seed);
        for e in 0..cfg.epochs {
            let epoch: Vec<usize> = order[e * rows..(e + 1) * rows]
                .iter()
                .map(|&i| i as usize)
                .collect();
            assert_eq!(epoch, shuffle.next_epoch(), "epoch {e}");
        }

        let meta: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("meta.json")).unwrap()).unwrap();
        assert_eq!(meta["train_rows"], rows);
        assert_eq!(meta["val_rows"], 3);
        assert_eq!(meta["hidden"], serde_json::json!(hidden));
        let lr: Vec<f64> = serde_json::from_value(meta["lr"].clone()).unwrap();
        assert_eq!(lr, (0..3).map(|e| lr_at(1e-3, e, 3)).collect::<Vec<_>>());
        assert_eq!(
            std::fs::read(dir.join("yo_val.f32")).unwrap().len(),
            4 * va.rows()
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
