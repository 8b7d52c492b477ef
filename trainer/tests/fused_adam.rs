//! `trainer::adam::FusedAdam` is burn's Adam, bit for bit (an integration test: the optimiser
//! module does not import the model module it serves).
use burn::optim::{AdamConfig, GradientsParams, ModuleOptimizer};
use burn::tensor::{Device, Tensor, TensorData};
use trainer::adam::FusedAdam;
use trainer::model::{ADAM_BETA_1, ADAM_BETA_2, ADAM_EPSILON, Cascade, Loss, Net, init_model};

fn bits(m: &Cascade) -> Vec<u32> {
    m.layers()
        .into_iter()
        .flat_map(|l| l.weights.into_iter().flatten().chain(l.bias))
        .map(f32::to_bits)
        .collect()
}

/// 40 steps on a small cascade with varying learning rates: burn's Adam and this one give the
/// same bits, and the weights did move.
#[test]
fn bit_identical_to_burns_adam() {
    // 160·128 weights: more than one parallel chunk of the update.
    let make = |d: &Device| Cascade::new(5, &[160, 128], d);
    let mut a = init_model(make, 7);
    let mut b = init_model(make, 7);
    let start = bits(&a);
    assert_eq!(start, bits(&b));
    let mut burn_adam: ModuleOptimizer = AdamConfig::new()
        .with_beta_1(ADAM_BETA_1)
        .with_beta_2(ADAM_BETA_2)
        .with_epsilon(ADAM_EPSILON)
        .init();
    let mut fused = ModuleOptimizer::from(FusedAdam {
        beta_1: ADAM_BETA_1,
        beta_2: ADAM_BETA_2,
        epsilon: ADAM_EPSILON,
    });
    let device = Device::flex().autodiff();
    for step in 0..40usize {
        let rows = 32;
        let x: Vec<f32> = (0..rows * 5)
            .map(|i| (((i * 37 + step * 11) % 97) as f32 / 48.0) - 1.0)
            .collect();
        let ym: Vec<f32> = (0..rows).map(|r| x[r * 5] * 0.5 - x[r * 5 + 1]).collect();
        let yo: Vec<f32> = (0..rows).map(|r| x[r * 5 + 2] * x[r * 5 + 3]).collect();
        let t = |v: &Vec<f32>, c: usize| {
            Tensor::<2>::from_data(TensorData::new(v.clone(), [rows, c]), &device)
        };
        let lr = 1e-3 * (1.0 + (step % 7) as f64);
        let (la, lb) = (
            a.losses(t(&x, 5), t(&ym, 1), t(&yo, 1), Loss::Mse),
            b.losses(t(&x, 5), t(&ym, 1), t(&yo, 1), Loss::Mse),
        );
        let ga = GradientsParams::from_grads((la.0 + la.1).backward(), &a);
        let gb = GradientsParams::from_grads((lb.0 + lb.1).backward(), &b);
        a = burn_adam.step(lr, a, ga);
        b = fused.step(lr, b, gb);
        assert_eq!(bits(&a), bits(&b), "step {step}");
    }
    assert_ne!(
        bits(&a),
        start,
        "the weights never moved: the test proves nothing"
    );
}
