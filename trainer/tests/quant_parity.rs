//! The trainer's independent integer reference agrees bit for bit with estimator-core's layers and
//! `CascadeNet::run`, and stays close to the float network it was quantized from. Uses a small network
//! trained in-process on a deterministic function (no dataset needed).
use estimator_core::nn::{Chain, Dense, Hidden, Output, Requant};
use estimator_core::normalize::{Envelope, TurbulenceEnvelope};
use estimator_core::{AngleNet, CascadeNet, Channel, Feature, FeatureValues, History, SensorFrame};
use trainer::model::{Cascade, Loss, Matrix, TrainConfig, float_forward, train};
use trainer::prep::{Angle, Prep, norm_for};
use trainer::quant::{QCascade, QLayer, format_vectors, parse_vectors, quantize_cascade, vectors};

const FEATS: [Feature; 3] = [
    Feature::Sensor(Channel::AccelZ),
    Feature::Sensor(Channel::Elevator),
    Feature::Sensor(Channel::GpsSpeed),
];

/// Deterministic frames sweeping three channels.
fn frames(n: usize) -> Vec<SensorFrame> {
    (0..n)
        .map(|i| {
            let t = i as f64 * 0.05;
            let mut si = [0.0; estimator_core::CHANNELS];
            si[Channel::AccelZ.index()] = -9.81 * (1.0 + 0.8 * (0.7 * t).sin());
            si[Channel::Elevator.index()] = 5.0 * (0.31 * t).cos();
            si[Channel::GpsSpeed.index()] = 200.0 + 60.0 * (0.13 * t).sin();
            si[Channel::GpsAlt.index()] = 3000.0;
            SensorFrame::from_si(i as u16, (i * 50) as u32, &si)
        })
        .collect()
}

/// Targets: a smooth nonlinear function of the inputs (mid in m/s, angle in degrees).
fn targets(f: &SensorFrame) -> (f64, f64) {
    let az = f.get(Channel::AccelZ) as f64 * 1e-5;
    let el = f.get(Channel::Elevator) as f64 * 1e-2;
    let v = f.get(Channel::GpsSpeed) as f64 * 1e-3;
    let w = -az * 2.0 + el * 0.5;
    (w, (w / v).atan().to_degrees() * 10.0)
}

fn setup(seed: u64, epochs: usize) -> (Prep, Cascade, Vec<Vec<f32>>) {
    let fr = frames(3000);
    let mut h = History::new();
    let vals: Vec<FeatureValues> = fr
        .iter()
        .map(|f| {
            let v = FeatureValues::compute(f, &h);
            h.push(f);
            v
        })
        .collect();
    // Prep fitted directly (no Flight needed): same construction as Prep::fit.
    let mut norm = Vec::new();
    let mut envelope = Vec::new();
    for f in FEATS {
        let xs: Vec<f64> = vals.iter().map(|v| v.get(f) as f64).collect();
        let m = xs.iter().sum::<f64>() / xs.len() as f64;
        let s = (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / xs.len() as f64).sqrt();
        norm.push(norm_for(m.round() as i32, s));
        envelope.push(Envelope {
            lo: vals.iter().map(|v| v.get(f)).min().unwrap(),
            hi: vals.iter().map(|v| v.get(f)).max().unwrap(),
        });
    }
    let ts: Vec<(f64, f64)> = fr.iter().map(targets).collect();
    let mm = ts.iter().map(|t| t.0 * 1000.0).sum::<f64>() / ts.len() as f64;
    let ms = (ts.iter().map(|t| (t.0 * 1000.0 - mm).powi(2)).sum::<f64>() / ts.len() as f64).sqrt();
    let om = ts.iter().map(|t| t.1 * 1000.0).sum::<f64>() / ts.len() as f64;
    let os = (ts.iter().map(|t| (t.1 * 1000.0 - om).powi(2)).sum::<f64>() / ts.len() as f64).sqrt();
    let prep = Prep {
        angle: Angle::Alpha,
        features: FEATS.to_vec(),
        norm,
        envelope,
        mid_norm: norm_for(mm.round() as i32, ms),
        out_center: om.round() as i32,
        out_sigma: os,
        out_range: Envelope {
            lo: -1_000_000,
            hi: 1_000_000,
        },
        turbulence: TurbulenceEnvelope::ANY,
        lift_scale: Envelope::ANY,
    };
    let mut x = Vec::new();
    let mut xs = Vec::new();
    for v in &vals {
        let mut r = Vec::new();
        prep.input(v, &mut r);
        x.extend_from_slice(&r);
        xs.push(r);
    }
    let ym: Vec<f32> = ts.iter().map(|t| prep.mid_z(t.0)).collect();
    let yo: Vec<f32> = ts.iter().map(|t| prep.out_z(t.1)).collect();
    let m = Matrix { x, ym, yo, n_in: 3 };
    let cfg = TrainConfig {
        epochs,
        batch: 64,
        lr: 3e-3,
        seed,
        label: "test".into(),
        progress: false,
        loss: Loss::Mse,
        replicas: None,
        bars: None,
    };
    let (model, _) = train(|d| Cascade::new(3, &[8, 4], d), &cfg, &m, &m);
    (prep, model, xs)
}

fn arr<const N: usize>(v: &[i8]) -> [i8; N] {
    std::array::from_fn(|i| v[i])
}

fn dense<const IN: usize, const OUT: usize>(l: &QLayer) -> Dense<IN, OUT> {
    assert_eq!((l.n_in(), l.n_out()), (IN, OUT));
    Dense::new(
        std::array::from_fn(|o| arr::<IN>(&l.weights[o])),
        std::array::from_fn(|o| l.bias[o]),
        std::array::from_fn(|o| Requant {
            mult: l.requant[o].0,
            shift: l.requant[o].1,
            offset: l.requant[o].2,
        }),
    )
}

type P1 = Chain<Hidden<3, 8>, Chain<Hidden<8, 4>, Output<4, 1>, 4>, 8>;
type P2 = Chain<Hidden<4, 8>, Chain<Hidden<8, 4>, Output<4, 1>, 4>, 8>;

fn core_net(q: &QCascade) -> CascadeNet<P1, P2, 3, 4> {
    let p = &q.prep;
    CascadeNet {
        features: FEATS,
        norm: [p.norm[0], p.norm[1], p.norm[2]],
        envelope: [p.envelope[0], p.envelope[1], p.envelope[2]],
        part1: Chain(
            Hidden(dense(&q.part1[0])),
            Chain(Hidden(dense(&q.part1[1])), Output(dense(&q.part1[2]))),
        ),
        mid_norm: p.mid_norm,
        part2: Chain(
            Hidden(dense(&q.part2[0])),
            Chain(Hidden(dense(&q.part2[1])), Output(dense(&q.part2[2]))),
        ),
        out_range: p.out_range,
        turbulence: p.turbulence,
        lift_scale: p.lift_scale,
    }
}

#[test]
fn training_is_bit_deterministic_and_seed_dependent() {
    let (_, a, _) = setup(7, 2);
    let (_, b, _) = setup(7, 2);
    let (_, c, _) = setup(8, 2);
    let wa = (a.part1.export(), a.part2.export());
    assert_eq!(wa, (b.part1.export(), b.part2.export()));
    assert_ne!(wa, (c.part1.export(), c.part2.export()));
}

#[test]
fn integer_reference_matches_estimator_core_and_tracks_float() {
    let (prep, model, xs) = setup(3, 15);
    let (p1, p2) = (model.part1.export(), model.part2.export());
    let q = quantize_cascade(&prep, &p1, &p2, &xs);
    let net = core_net(&q);
    let mut fr = frames(3000);
    // Edge cases: every used channel at the ends of its wire range.
    for c in [Channel::AccelZ, Channel::Elevator, Channel::GpsSpeed] {
        let (lo, hi) = c.raw_range();
        for v in [lo, hi] {
            let mut f = fr[10];
            f.raw[c.index()] = v;
            fr.push(f);
        }
    }
    let mut max_err_mdeg = 0f64;
    let mut h = History::new();
    for (i, f) in fr.iter().enumerate() {
        let v = FeatureValues::compute(f, &h);
        h.push(f);
        let r = q.reference(&v);
        assert_eq!(net.run(&v), (r.mid, r.angle, r.clamped), "frame {i}");
        if i < xs.len() {
            let mid = float_forward(&p1, &xs[i], |_, _| {});
            let mut x2 = xs[i].clone();
            x2.push(mid);
            let out = float_forward(&p2, &x2, |_, _| {});
            let deg = prep.out_deg(out as f64);
            max_err_mdeg = max_err_mdeg.max((deg * 1000.0 - r.angle as f64).abs());
        }
    }
    // int8 vs float: within 2% of the angle's training standard deviation.
    assert!(
        max_err_mdeg < 0.02 * prep.out_sigma + 5.0,
        "int8 vs float {max_err_mdeg} mdeg, sigma {}",
        prep.out_sigma
    );
    // The speed-floor flags mark a frame clamped as `Estimator` does: low GPS speed for a model
    // reading GPS speed, low ground speed (EGI velocity) for a model reading the EGI velocity.
    let mut v = FeatureValues::compute(&fr[10], &History::new());
    assert!(!q.reference(&v).clamped && !net.run(&v).2);
    v.low_speed = true;
    assert!(q.reference(&v).clamped && net.run(&v).2);
    v.low_speed = false;
    v.low_ground_speed = true;
    assert!(
        !q.reference(&v).clamped && !net.run(&v).2,
        "no velocity input"
    );
    // The same network reading the EGI north velocity in its third input, with an envelope that
    // cannot clamp it: only the flag can mark the frame.
    let mut qv = q.clone();
    qv.prep.features[2] = Feature::Sensor(Channel::VelNorth);
    qv.prep.envelope[2] = Envelope::ANY;
    let mut nv = core_net(&qv);
    nv.features[2] = Feature::Sensor(Channel::VelNorth);
    v.low_ground_speed = false;
    assert!(!qv.reference(&v).clamped && !nv.run(&v).2);
    v.low_ground_speed = true;
    let (r, n) = (qv.reference(&v), nv.run(&v));
    assert!(
        r.clamped && n.2,
        "a model reading the EGI velocity: reference {r:?}, core {n:?}"
    );
    // The filter's lift scale outside its recorded training range marks the frame in both, though
    // it is not an input (these frames run no filter: the feature reads 0).
    v.low_ground_speed = false;
    assert!(!q.reference(&v).clamped && !net.run(&v).2);
    // At both edges of the range (0 inside) and one LSB beyond each.
    for (lo, hi, out) in [(0, 5, false), (-5, 0, false), (1, 5, true), (-5, -1, true)] {
        let mut ql = q.clone();
        ql.prep.lift_scale = Envelope { lo, hi };
        let (r, n) = (ql.reference(&v), core_net(&ql).run(&v));
        assert_eq!((r.clamped, n.2), (out, out), "lift scale range {lo}..={hi}");
        assert_eq!((r.mid, r.angle), (n.0, n.1));
    }
    // Vectors round-trip through the text format.
    let seq: Vec<(bool, SensorFrame)> = fr[..50]
        .iter()
        .enumerate()
        .map(|(i, f)| (i % 20 == 0, *f))
        .collect();
    let vs = vectors(&q, &q, &seq);
    let text = format_vectors(&vs, estimator_core::Suite::Egi, "test\nheader");
    assert_eq!(parse_vectors(&text).unwrap(), vs);
    // An egi120 file carries the sub-samples too (112 numbers a line), bit for bit.
    let mut vs120 = vs.clone();
    for (n, v) in vs120.iter_mut().enumerate() {
        for (k, r) in v.frame.sub.raw.iter_mut().flatten().enumerate() {
            *r = (n * 1000 + k) as i32 - 40_000;
        }
        v.frame.sub.valid = estimator_core::channels::Subsamples::ALL_VALID & !(n as u16 & 7);
    }
    let text = format_vectors(&vs120, estimator_core::Suite::Egi120, "t120");
    assert!(
        text.lines()
            .filter(|l| !l.starts_with('#'))
            .all(|l| l.split_whitespace().count() == 112)
    );
    assert_eq!(parse_vectors(&text).unwrap(), vs120);
    // A Table 1 file carries the Table 1 channels only (26 numbers a line, as before the EGI
    // suite): the frames come back as a Table 1 sender delivers them.
    let text = format_vectors(&vs, estimator_core::Suite::Table1, "t1");
    let back = parse_vectors(&text).unwrap();
    assert!(
        text.lines()
            .filter(|l| !l.starts_with('#'))
            .all(|l| l.split_whitespace().count() == 26)
    );
    for (b, v) in back.iter().zip(&vs) {
        assert_eq!(
            b.frame,
            v.frame.restricted_to(estimator_core::Suite::Table1)
        );
        assert_eq!((b.alpha, b.beta), (v.alpha, v.beta));
    }
}
