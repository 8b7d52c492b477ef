//! The networks in burn (flex backend: pure Rust, bit-deterministic): a plain MLP and the cascade of
//! Fig. 7 (part 1 → intermediate; part 2 on the features plus the intermediate), trained jointly on
//! MSE(intermediate) + MSE(angle) with Adam.
use burn::module::{Module, Param};
use burn::nn::{Linear, LinearConfig};
use burn::optim::{GradientsParams, ModuleOptimizer};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use indicatif::ProgressBar;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// A float dense layer as exported from burn: `weights[o][i]`, `bias[o]`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FloatLayer {
    pub weights: Vec<Vec<f32>>,
    pub bias: Vec<f32>,
}

impl FloatLayer {
    pub fn n_in(&self) -> usize {
        self.weights.first().map_or(0, |r| r.len())
    }
    pub fn n_out(&self) -> usize {
        self.weights.len()
    }
}

/// Float forward pass of an exported MLP (ReLU between layers), recording every hidden activation.
pub fn float_forward(
    layers: &[FloatLayer],
    x: &[f32],
    mut hidden: impl FnMut(usize, &[f32]),
) -> f32 {
    let mut cur = x.to_vec();
    for (k, l) in layers.iter().enumerate() {
        let last = k + 1 == layers.len();
        let mut y: Vec<f32> = l
            .weights
            .iter()
            .zip(&l.bias)
            .map(|(row, b)| row.iter().zip(&cur).fold(*b, |s, (w, x)| s + w * x))
            .collect();
        if !last {
            for v in &mut y {
                *v = v.max(0.0);
            }
            hidden(k, &y);
        }
        cur = y;
    }
    cur.first().copied().unwrap_or(0.0)
}

#[derive(Module, Debug)]
pub struct Mlp {
    layers: Vec<Linear>,
}

impl Mlp {
    /// `dims = [in, h1, ..., out]`.
    pub fn new(dims: &[usize], device: &Device) -> Mlp {
        Mlp {
            layers: dims
                .windows(2)
                .map(|w| LinearConfig::new(w[0], w[1]).init(device))
                .collect(),
        }
    }

    pub fn forward(&self, mut x: Tensor<2>) -> Tensor<2> {
        let n = self.layers.len();
        for (k, l) in self.layers.iter().enumerate() {
            x = l.forward(x);
            if k + 1 < n {
                x = relu(x);
            }
        }
        x
    }

    /// An MLP holding exported layers ([`Mlp::export`] gives them back bit for bit), on `device`;
    /// its parameters train from there.
    pub fn from_layers(layers: &[FloatLayer], device: &Device) -> Mlp {
        Mlp {
            layers: layers
                .iter()
                .map(|l| {
                    let (n_in, n_out) = (l.n_in(), l.n_out());
                    // `Linear` stores `[in, out]`: element (i, o) at i·n_out + o.
                    let w: Vec<f32> = (0..n_in)
                        .flat_map(|i| l.weights.iter().map(move |row| row[i]))
                        .collect();
                    Linear {
                        weight: Param::from_data(TensorData::new(w, [n_in, n_out]), device),
                        bias: Some(Param::from_data(
                            TensorData::new(l.bias.clone(), [n_out]),
                            device,
                        )),
                    }
                })
                .collect(),
        }
    }

    /// Weights out of burn (`Linear` stores `[in, out]`, y = xW + b) into `[out][in]` rows.
    pub fn export(&self) -> Vec<FloatLayer> {
        self.layers
            .iter()
            .map(|l| {
                let [n_in, n_out] = l.weight.val().dims();
                let w = l
                    .weight
                    .val()
                    .into_data()
                    .try_to_vec::<f32>()
                    .unwrap_or_default();
                let b = l
                    .bias
                    .as_ref()
                    .map(|b| b.val().into_data().try_to_vec::<f32>().unwrap_or_default())
                    .unwrap_or_else(|| vec![0.0; n_out]);
                FloatLayer {
                    weights: (0..n_out)
                        .map(|o| (0..n_in).map(|i| w[i * n_out + o]).collect())
                        .collect(),
                    bias: b,
                }
            })
            .collect()
    }
}

/// Paper Fig. 7: one network per angle, two parts.
#[derive(Module, Debug)]
pub struct Cascade {
    pub part1: Mlp,
    pub part2: Mlp,
}

impl Cascade {
    pub fn new(n_in: usize, hidden: &[usize], device: &Device) -> Cascade {
        let dims = |n: usize| {
            let mut d = vec![n];
            d.extend_from_slice(hidden);
            d.push(1);
            d
        };
        Cascade {
            part1: Mlp::new(&dims(n_in), device),
            part2: Mlp::new(&dims(n_in + 1), device),
        }
    }

    /// A cascade holding exported parts (a saved model's float layers), to train further.
    pub fn from_layers(part1: &[FloatLayer], part2: &[FloatLayer], device: &Device) -> Cascade {
        Cascade {
            part1: Mlp::from_layers(part1, device),
            part2: Mlp::from_layers(part2, device),
        }
    }

    /// The same cascade with every parameter but those of part 2's output layer frozen (no
    /// gradient, so the optimizer leaves them).
    pub fn output_layer_only(self) -> Cascade {
        let n = self.part2.layers.len();
        Cascade {
            part1: self.part1.no_grad(),
            part2: Mlp {
                layers: self
                    .part2
                    .layers
                    .into_iter()
                    .enumerate()
                    .map(|(k, l)| if k + 1 == n { l } else { l.no_grad() })
                    .collect(),
            },
        }
    }

    /// (intermediate, angle), both normalised.
    pub fn forward(&self, x: Tensor<2>) -> (Tensor<2>, Tensor<2>) {
        let mid = self.part1.forward(x.clone());
        let out = self.part2.forward(Tensor::cat(vec![x, mid.clone()], 1));
        (mid, out)
    }
}

/// What is trained: the cascade (both losses) or a plain MLP (angle loss only).
pub trait Net: Module + Sized + Send + Sync {
    /// Per-head losses `[intermediate, angle]` (a plain MLP reports 0 for the intermediate).
    fn losses(
        &self,
        x: Tensor<2>,
        ym: Tensor<2>,
        yo: Tensor<2>,
        loss: Loss,
    ) -> (Tensor<1>, Tensor<1>);
    /// Predicted normalised (intermediate, angle) per row.
    fn predict(&self, x: Tensor<2>) -> (Vec<f32>, Vec<f32>);
    /// Float layers; reading them also forces burn's lazy parameter initialisation.
    fn layers(&self) -> Vec<FloatLayer>;
}

/// What the training minimises, per head.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Loss {
    /// Mean squared error (the paper's loss; the default).
    #[default]
    Mse,
    /// Mean absolute error: the metric every accuracy table reports. Its minimiser is the
    /// conditional median rather than the mean, which an error made of heavy-tailed turbulence
    /// pulls less.
    L1,
}

impl Loss {
    pub fn parse(s: &str) -> Option<Loss> {
        match s {
            "mse" => Some(Loss::Mse),
            "l1" => Some(Loss::L1),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Loss::Mse => "mse",
            Loss::L1 => "l1",
        }
    }

    fn of(self, a: Tensor<2>, b: Tensor<2>) -> Tensor<1> {
        let d = a - b;
        match self {
            Loss::Mse => (d.clone() * d).mean(),
            Loss::L1 => d.abs().mean(),
        }
    }

    /// The same per row, in f64, for the validation pass.
    fn row(self, d: f64) -> f64 {
        match self {
            Loss::Mse => d * d,
            Loss::L1 => d.abs(),
        }
    }
}

fn to_vec(t: Tensor<2>) -> Vec<f32> {
    t.into_data().try_to_vec::<f32>().unwrap_or_default()
}

impl Net for Cascade {
    fn losses(
        &self,
        x: Tensor<2>,
        ym: Tensor<2>,
        yo: Tensor<2>,
        loss: Loss,
    ) -> (Tensor<1>, Tensor<1>) {
        let (m, o) = self.forward(x);
        (loss.of(m, ym), loss.of(o, yo))
    }
    fn predict(&self, x: Tensor<2>) -> (Vec<f32>, Vec<f32>) {
        let (m, o) = self.forward(x);
        (to_vec(m), to_vec(o))
    }
    fn layers(&self) -> Vec<FloatLayer> {
        let mut l = self.part1.export();
        l.extend(self.part2.export());
        l
    }
}

impl Net for Mlp {
    fn losses(
        &self,
        x: Tensor<2>,
        ym: Tensor<2>,
        yo: Tensor<2>,
        loss: Loss,
    ) -> (Tensor<1>, Tensor<1>) {
        let o = self.forward(x);
        (loss.of(ym.clone(), ym), loss.of(o, yo))
    }
    fn predict(&self, x: Tensor<2>) -> (Vec<f32>, Vec<f32>) {
        let o = to_vec(self.forward(x));
        (vec![0.0; o.len()], o)
    }
    fn layers(&self) -> Vec<FloatLayer> {
        self.export()
    }
}

/// Rows of a design matrix with both targets.
pub struct Matrix {
    pub x: Vec<f32>,
    pub ym: Vec<f32>,
    pub yo: Vec<f32>,
    pub n_in: usize,
}

impl Matrix {
    pub fn rows(&self) -> usize {
        self.yo.len()
    }
}

#[derive(Debug, Clone)]
pub struct TrainConfig {
    pub epochs: usize,
    pub batch: usize,
    pub lr: f64,
    pub seed: u64,
    pub label: String,
    pub progress: bool,
    pub loss: Loss,
    /// Replicas each batch is split over: 1, one forward and backward pass; 2, its two halves at
    /// once, each on its own copy of the model, gradients summed. `None`: [`auto_replicas`].
    pub replicas: Option<usize>,
    /// Where the progress bar goes when trainings run side by side (`trainer train` trains α and
    /// β at once); `None`: a bar of its own.
    pub bars: Option<indicatif::MultiProgress>,
}

/// Per-epoch mean losses `[mid, angle]` of the training batches and of the validation set.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Curves {
    pub train: Vec<[f64; 2]>,
    pub val: Vec<[f64; 2]>,
    pub epoch_s: Vec<f64>,
    pub best_epoch: usize,
    /// Replicas each batch was split over ([`TrainConfig::replicas`]).
    pub replicas: usize,
}

impl Curves {
    /// Mean epoch time over epochs 2..N (the first carries warm-up); NaN with fewer than 2.
    pub fn mean_after_warmup(&self) -> f64 {
        let rest = self.epoch_s.get(1..).unwrap_or(&[]);
        rest.iter().sum::<f64>() / rest.len() as f64
    }
}

/// Predictions (normalised) in batches on the plain device.
pub fn predict_all<M: Net>(model: &M, x: &[f32], n_in: usize) -> (Vec<f32>, Vec<f32>) {
    let dev = Device::flex();
    let n = x.len() / n_in.max(1);
    let (mut pm, mut po) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for start in (0..n).step_by(8192) {
        let end = (start + 8192).min(n);
        let t = Tensor::<2>::from_data(
            TensorData::new(x[start * n_in..end * n_in].to_vec(), [end - start, n_in]),
            &dev,
        );
        let (m, o) = model.predict(t);
        pm.extend(m);
        po.extend(o);
    }
    (pm, po)
}

/// Mean loss per head `[intermediate, angle]` of `model` on the rows of `val`.
pub fn val_losses<M: Net>(model: &M, val: &Matrix, loss: Loss) -> [f64; 2] {
    let (pm, po) = predict_all(model, &val.x, val.n_in);
    let n = val.rows().max(1) as f64;
    let m = pm
        .iter()
        .zip(&val.ym)
        .map(|(p, y)| loss.row((p - y) as f64))
        .sum::<f64>()
        / n;
    let o = po
        .iter()
        .zip(&val.yo)
        .map(|(p, y)| loss.row((p - y) as f64))
        .sum::<f64>()
        / n;
    [m, o]
}

/// Widest layer from which [`auto_replicas`] splits each batch over two replicas.
pub const SPLIT_FROM_WIDTH: usize = 256;

/// Replicas for a model of these layers when the configuration does not say: 2 when a layer has
/// at least [`SPLIT_FROM_WIDTH`] outputs (the paper-size α cascade: its element-wise work, which
/// burn-flex runs on one thread below 4 Mi elements, then runs on both cores; 20-25 % less time
/// per epoch on 2 cores, docs/training-speed.md), else 1 (small layers: the split's copies and
/// extra operations cost more than they save, and the shipped network stays reproducible bit for
/// bit). A rule on the model alone, never on the thread count, so a seed gives the same weights on
/// any machine.
pub fn auto_replicas(layers: &[FloatLayer]) -> usize {
    if layers.iter().any(|l| l.n_out() >= SPLIT_FROM_WIDTH) {
        2
    } else {
        1
    }
}

/// One batch's forward and backward pass on `model`: rows `x` (`n_in` per row) with targets
/// `ym`, `yo`; the losses are scaled by `weight` before the backward pass. Returns the unscaled
/// per-head losses and the gradients.
#[allow(clippy::too_many_arguments)]
fn batch_step<M: Net>(
    model: &M,
    x: &[f32],
    ym: &[f32],
    yo: &[f32],
    n_in: usize,
    weight: f32,
    loss: Loss,
    device: &Device,
) -> (f64, f64, GradientsParams) {
    let b = yo.len();
    let x = Tensor::<2>::from_data(TensorData::new(x.to_vec(), [b, n_in]), device);
    let ym = Tensor::<2>::from_data(TensorData::new(ym.to_vec(), [b, 1]), device);
    let yo = Tensor::<2>::from_data(TensorData::new(yo.to_vec(), [b, 1]), device);
    let (lm, lo) = model.losses(x, ym, yo, loss);
    let total = lm.clone() + lo.clone();
    let total = if weight == 1.0 { total } else { total * weight };
    let (lm, lo) = (
        lm.into_scalar::<f32>() as f64,
        lo.into_scalar::<f32>() as f64,
    );
    (lm, lo, GradientsParams::from_grads(total.backward(), model))
}

/// The same batch in `parts` contiguous slices, one per replica, run on the pool's threads: the
/// first slice on `model`, the others on forks of it (same values, each its own autodiff graph, so
/// the backward passes do not share a lock). Each slice's loss is weighted by its share of the
/// rows, so the summed gradients are the whole batch's mean-loss gradients; they are added in slice
/// order, so the result does not depend on the number of threads or on which thread ran what.
#[allow(clippy::too_many_arguments)]
fn batch_step_split<M: Net>(
    model: &M,
    x: &[f32],
    ym: &[f32],
    yo: &[f32],
    n_in: usize,
    parts: usize,
    loss: Loss,
    device: &Device,
) -> (f64, f64, GradientsParams) {
    use rayon::prelude::*;
    let b = yo.len();
    let parts = parts.clamp(1, b.max(1));
    let bounds: Vec<(usize, usize)> = (0..parts)
        .map(|k| (k * b / parts, (k + 1) * b / parts))
        .collect();
    let results: Vec<(f64, f64, f64, GradientsParams)> = bounds
        .par_iter()
        .enumerate()
        .map(|(k, &(l, h))| {
            let w = (h - l) as f32 / b as f32;
            let step = |m: &M| {
                let x = &x[l * n_in..h * n_in];
                batch_step(m, x, &ym[l..h], &yo[l..h], n_in, w, loss, device)
            };
            let (lm, lo, g) = if k == 0 {
                step(model)
            } else {
                step(&model.clone().fork(device))
            };
            (lm, lo, w as f64, g)
        })
        .collect();
    let (mut sm, mut so) = (0.0, 0.0);
    let mut grads: Option<GradientsParams> = None;
    for (lm, lo, w, g) in results {
        sm += lm * w;
        so += lo * w;
        grads = Some(match grads {
            None => g,
            Some(acc) => sum_grads(model, acc, g),
        });
    }
    (sm, so, grads.unwrap_or_default())
}

/// `a + b` per parameter of `model`; a parameter with a gradient in only one keeps that one.
fn sum_grads<M: Module>(model: &M, a: GradientsParams, b: GradientsParams) -> GradientsParams {
    struct Sum {
        a: GradientsParams,
        b: GradientsParams,
        out: GradientsParams,
    }
    impl burn::module::ModuleVisitor for Sum {
        fn visit_float<const D: usize>(&mut self, param: &burn::module::Param<Tensor<D>>) {
            let sum = match (self.a.remove::<D>(param.id), self.b.remove::<D>(param.id)) {
                (Some(a), Some(b)) => Some(a + b),
                (Some(g), None) | (None, Some(g)) => Some(g),
                (None, None) => None,
            };
            if let Some(g) = sum {
                self.out.register(param.id, g);
            }
        }
    }
    let mut v = Sum {
        a,
        b,
        out: GradientsParams::new(),
    };
    model.visit(&mut v);
    v.out
}

static INIT_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Adam's constants (burn's defaults, spelled out so `trainer bench-train` can hand them to PyTorch).
pub const ADAM_BETA_1: f32 = 0.9;
pub const ADAM_BETA_2: f32 = 0.999;
pub const ADAM_EPSILON: f32 = 1e-5;

/// Learning rate of `epoch` (0-based) of `epochs`: cosine decay from `lr` to 5 % of it.
pub fn lr_at(lr: f64, epoch: usize, epochs: usize) -> f64 {
    lr * (0.05 + 0.95 * 0.5 * (1.0 + (std::f64::consts::PI * epoch as f64 / epochs as f64).cos()))
}

/// The seeded mini-batch order: the row indices, shuffled anew (ChaCha8) at every epoch.
pub struct Shuffle {
    rng: ChaCha8Rng,
    order: Vec<usize>,
}

impl Shuffle {
    pub fn new(rows: usize, seed: u64) -> Shuffle {
        Shuffle {
            rng: ChaCha8Rng::seed_from_u64(seed),
            order: (0..rows).collect(),
        }
    }
    /// The next epoch's row order.
    pub fn next_epoch(&mut self) -> &[usize] {
        self.order.shuffle(&mut self.rng);
        &self.order
    }
}

/// A seeded model on the autodiff device, its parameters materialised under the init lock.
pub fn init_model<M: Net>(init: impl FnOnce(&Device) -> M, seed: u64) -> M {
    let device = Device::flex().autodiff();
    // The backend's RNG is process-global: seeding and initialising under one lock keeps concurrent
    // trainings (tests, report runs) deterministic.
    let _guard = INIT_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    device.seed(seed);
    Device::flex().seed(seed);
    let m = init(&device);
    // Parameters initialise lazily: materialise them while the seeded RNG is ours.
    let _ = m.layers();
    m
}

/// Trains with Adam (cosine-decayed learning rate), mini-batches shuffled by a seeded ChaCha8, and keeps
/// the epoch with the lowest validation loss (sum of both heads). Deterministic for a given seed, on
/// any number of threads.
///
/// The loop runs as a worker of its own rayon pool (as many threads as the global pool: all cores,
/// `RAYON_NUM_THREADS`, or `bench-train --threads`). burn-flex splits its larger matrix products over
/// the current pool; called from outside a pool, every product wakes two sleeping workers and parks
/// the caller. Inside, the caller computes one half itself. The paper-size α cascade's epoch on 2
/// cores: 10.8 s outside, 7.9 s inside (docs/results/training-speed.md).
pub fn train<M: Net + Send>(
    init: impl FnOnce(&Device) -> M + Send,
    cfg: &TrainConfig,
    train: &Matrix,
    val: &Matrix,
) -> (M, Curves) {
    train_with(init, cfg, train, val, |_| {})
}

/// [`train`], calling `after_epoch(epoch)` after each epoch, outside its timing
/// (`trainer bench-train` runs PyTorch's epoch there, in lockstep).
pub fn train_with<M: Net + Send>(
    init: impl FnOnce(&Device) -> M + Send,
    cfg: &TrainConfig,
    train: &Matrix,
    val: &Matrix,
    after_epoch: impl FnMut(usize) + Send,
) -> (M, Curves) {
    let threads = rayon::current_num_threads();
    match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(pool) => pool.install(|| train_here(init, cfg, train, val, after_epoch)),
        // No threads to be had: the same loop on the caller's thread alone.
        Err(_) => train_here(init, cfg, train, val, after_epoch),
    }
}

fn train_here<M: Net>(
    init: impl FnOnce(&Device) -> M,
    cfg: &TrainConfig,
    train: &Matrix,
    val: &Matrix,
    mut after_epoch: impl FnMut(usize),
) -> (M, Curves) {
    let device = Device::flex().autodiff();
    let mut model = init_model(init, cfg.seed);
    // burn's Adam, bit for bit, in one pass per parameter (crate::adam).
    let mut optim = ModuleOptimizer::from(crate::adam::FusedAdam {
        beta_1: ADAM_BETA_1,
        beta_2: ADAM_BETA_2,
        epsilon: ADAM_EPSILON,
    });
    let mut shuffle = Shuffle::new(train.rows(), cfg.seed);
    let replicas = cfg
        .replicas
        .unwrap_or_else(|| auto_replicas(&model.layers()));
    let mut curves = Curves {
        replicas,
        ..Curves::default()
    };
    let mut best: Option<(f64, M)> = None;
    let pb = if cfg.progress {
        let pb = ProgressBar::new(cfg.epochs as u64);
        let pb = match &cfg.bars {
            Some(bars) => bars.add(pb),
            None => pb,
        };
        hil_sim::progress::style(&pb, "epochs");
        pb.set_prefix(cfg.label.clone());
        hil_sim::progress::log_when_not_a_terminal(&pb, "epochs");
        pb
    } else {
        ProgressBar::hidden()
    };
    let n_in = train.n_in;
    let (mut bx, mut bm, mut bo) = (Vec::new(), Vec::new(), Vec::new());
    for epoch in 0..cfg.epochs {
        let t0 = Instant::now();
        let lr = lr_at(cfg.lr, epoch, cfg.epochs);
        let (mut sm, mut so, mut nb) = (0f64, 0f64, 0usize);
        for chunk in shuffle.next_epoch().chunks(cfg.batch) {
            bx.clear();
            bm.clear();
            bo.clear();
            for &i in chunk {
                bx.extend_from_slice(&train.x[i * n_in..(i + 1) * n_in]);
                bm.push(train.ym[i]);
                bo.push(train.yo[i]);
            }
            let (lm, lo, grads) = if replicas >= 2 && chunk.len() >= 2 {
                batch_step_split(&model, &bx, &bm, &bo, n_in, replicas, cfg.loss, &device)
            } else {
                batch_step(&model, &bx, &bm, &bo, n_in, 1.0, cfg.loss, &device)
            };
            sm += lm;
            so += lo;
            nb += 1;
            model = optim.step(lr, model, grads);
        }
        let nbf = nb.max(1) as f64;
        curves.train.push([sm / nbf, so / nbf]);
        let v = if val.rows() > 0 {
            val_losses(&model.valid(), val, cfg.loss)
        } else {
            [sm / nbf, so / nbf]
        };
        curves.val.push(v);
        curves.epoch_s.push(t0.elapsed().as_secs_f64());
        let score = v[0] + v[1];
        if best.as_ref().is_none_or(|(s, _)| score < *s) {
            best = Some((score, model.valid()));
            curves.best_epoch = epoch;
        }
        pb.set_message(format!(
            "train {:.4}/{:.4} val {:.4}/{:.4}",
            sm / nbf,
            so / nbf,
            v[0],
            v[1]
        ));
        pb.inc(1);
        after_epoch(epoch);
    }
    pb.finish();
    let model = match best {
        Some((_, m)) => m,
        None => model.valid(),
    };
    (model, curves)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trained cascade's exported layers, loaded back, are the same model: the same layers bit
    /// for bit and the same answers (`trainer finetune` starts from them).
    #[test]
    fn exported_layers_load_back_bit_for_bit() {
        let m = init_model(|d| Cascade::new(5, &[7, 3], d), 3);
        let (p1, p2) = (m.part1.export(), m.part2.export());
        let back = Cascade::from_layers(&p1, &p2, &Device::flex().autodiff());
        assert_eq!(back.part1.export(), p1);
        assert_eq!(back.part2.export(), p2);
        let x: Vec<f32> = (0..20).map(|k| (k as f32 * 0.37).sin()).collect();
        assert_eq!(predict_all(&m, &x, 5), predict_all(&back, &x, 5));
        // model.json keeps them as JSON numbers: they read back bit for bit.
        let text = serde_json::to_string(&p1).unwrap();
        assert_eq!(serde_json::from_str::<Vec<FloatLayer>>(&text).unwrap(), p1);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let many: Vec<f32> = (0..100_000)
            .map(|_| f32::from_bits(rand::Rng::random::<u32>(&mut rng) & 0xbfff_ffff))
            .filter(|v| v.is_finite())
            .collect();
        let back: Vec<f32> = serde_json::from_str(&serde_json::to_string(&many).unwrap()).unwrap();
        assert!(
            many.iter()
                .zip(&back)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }

    /// Rows whose angle target is 0 four times in five and 5 otherwise, from inputs that cannot
    /// tell them apart: the best constant answer is the mean (1) under MSE and the median (0)
    /// under L1.
    fn skewed() -> Matrix {
        let n = 500;
        Matrix {
            x: vec![0.5; n],
            ym: vec![0.0; n],
            yo: (0..n).map(|i| if i % 5 == 0 { 5.0 } else { 0.0 }).collect(),
            n_in: 1,
        }
    }

    fn fit(loss: Loss) -> f32 {
        let m = skewed();
        let cfg = TrainConfig {
            epochs: 40,
            batch: 50,
            lr: 1e-2,
            seed: 3,
            label: String::new(),
            progress: false,
            loss,
            replicas: None,
            bars: None,
        };
        let (model, curves) = train(|d| Cascade::new(1, &[4], d), &cfg, &m, &m);
        // The validation loss is the training loss's own kind (at the epoch `train` returns).
        let last = curves
            .val
            .get(curves.best_epoch)
            .copied()
            .unwrap_or_default();
        let (_, out) = predict_all(&model, &[0.5], 1);
        let o = out.first().copied().unwrap_or(f32::NAN);
        let expected = match loss {
            Loss::Mse => m.yo.iter().map(|y| f64::from(y - o).powi(2)).sum::<f64>(),
            Loss::L1 => m.yo.iter().map(|y| f64::from(y - o).abs()).sum::<f64>(),
        } / m.rows() as f64;
        assert!(
            (last[1] - expected).abs() < 1e-4,
            "{loss:?}: {last:?} vs {expected}"
        );
        o
    }

    #[test]
    fn mse_learns_the_mean_and_l1_the_median() {
        let mean = fit(Loss::Mse);
        let median = fit(Loss::L1);
        assert!((mean - 1.0).abs() < 0.1, "MSE answer {mean}");
        assert!(median.abs() < 0.1, "L1 answer {median}");
    }

    #[test]
    fn losses_parse_by_name() {
        for l in [Loss::Mse, Loss::L1] {
            assert_eq!(Loss::parse(l.name()), Some(l));
        }
        assert_eq!(Loss::parse("huber"), None);
    }

    /// A small regression problem: 3 inputs, both targets smooth functions of them.
    fn ramp(rows: usize) -> Matrix {
        let x: Vec<f32> = (0..rows * 3)
            .map(|i| ((i * 37 % 101) as f32 / 50.0) - 1.0)
            .collect();
        let ym = x.chunks(3).map(|r| r[0] - 0.5 * r[1]).collect();
        let yo = x.chunks(3).map(|r| r[0] * r[2] + 0.3 * r[1]).collect();
        Matrix { x, ym, yo, n_in: 3 }
    }

    fn run(
        replicas: usize,
        epochs: usize,
        batch: usize,
        threads: usize,
    ) -> (Vec<FloatLayer>, Curves) {
        let m = ramp(96);
        let cfg = TrainConfig {
            epochs,
            batch,
            lr: 1e-2,
            seed: 11,
            label: String::new(),
            progress: false,
            loss: Loss::Mse,
            replicas: Some(replicas),
            bars: None,
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (model, curves) = pool.install(|| train(|d| Cascade::new(3, &[8, 4], d), &cfg, &m, &m));
        (model.layers(), curves)
    }

    /// Every gradient of a model, parameter after parameter.
    fn flat_grads<M: Module>(model: &M, grads: &GradientsParams) -> Vec<f32> {
        struct Flat<'a>(&'a GradientsParams, Vec<f32>);
        impl burn::module::ModuleVisitor for Flat<'_> {
            fn visit_float<const D: usize>(&mut self, param: &burn::module::Param<Tensor<D>>) {
                let g = self
                    .0
                    .get::<D>(param.id)
                    .map(|t| t.into_data().try_to_vec::<f32>().unwrap_or_default());
                self.1.extend(g.unwrap_or_default());
            }
        }
        let mut v = Flat(grads, Vec::new());
        model.visit(&mut v);
        v.1
    }

    /// A batch of 96 rows in one pass and split over 2 and over 5 replicas (slices of unequal
    /// size): the same gradient of every parameter and the same batch losses, up to rounding.
    #[test]
    fn a_split_batch_has_the_whole_batch_gradient() {
        let m = ramp(96);
        let device = Device::flex().autodiff();
        let model = init_model(|d| Cascade::new(3, &[8, 4], d), 11);
        let (wm, wo, wg) = batch_step(&model, &m.x, &m.ym, &m.yo, 3, 1.0, Loss::Mse, &device);
        let whole = flat_grads(&model, &wg);
        let scale = whole.iter().map(|g| g.abs()).fold(0.0, f32::max);
        assert_eq!(
            whole.len(),
            3 * 8 + 8 + 8 * 4 + 4 + 4 + 1 + 4 * 8 + 8 + 8 * 4 + 4 + 4 + 1
        );
        assert!(scale > 1e-2, "gradients too small to compare: {scale}");
        for r in [2, 5] {
            let (sm, so, sg) =
                batch_step_split(&model, &m.x, &m.ym, &m.yo, 3, r, Loss::Mse, &device);
            let split = flat_grads(&model, &sg);
            assert_eq!(split.len(), whole.len(), "{r} replicas");
            let d = whole
                .iter()
                .zip(&split)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max);
            assert!(
                d < 1e-5 * scale,
                "{r} replicas: gradients differ by {d} (scale {scale})"
            );
            assert!(
                (sm - wm).abs() < 1e-6 && (so - wo).abs() < 1e-6,
                "{r}: {sm} {so} vs {wm} {wo}"
            );
        }
    }

    /// Split training gives the same bits on one thread as on two (which replica ran where, and
    /// when, does not enter), and is not the one-pass result bit for bit (the split really ran).
    #[test]
    fn split_training_is_the_same_on_any_thread_count() {
        let (one, _) = run(2, 3, 16, 1);
        let (two, _) = run(2, 3, 16, 2);
        assert_eq!(one, two);
        let (whole, _) = run(1, 3, 16, 2);
        assert_ne!(one, whole);
    }

    #[test]
    fn only_wide_models_split_by_default() {
        let layers = |hidden: &[usize]| init_model(|d| Cascade::new(10, hidden, d), 1).layers();
        assert_eq!(auto_replicas(&layers(&[512, 256, 128, 64, 32])), 2);
        assert_eq!(auto_replicas(&layers(&[64, 32, 16])), 1);
        assert_eq!(auto_replicas(&layers(&[255])), 1);
        assert_eq!(auto_replicas(&layers(&[256])), 2);
    }
}
