//! Sensor error models measured back from long samples (no JSBSim needed).

use estimator_core::Channel;
use hil_sim::sensors::{SensorConfig, SensorInput, SensorModel};

fn level_input() -> SensorInput {
    SensorInput {
        f_cg_mps2: [0.0, 0.0, -9.80665],
        gps_speed_mps: 200.0,
        alt_msl_m: 5000.0,
        elevator_deg: -1.234,
        throttle_norm: 0.4321,
        ..SensorInput::default()
    }
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, var.sqrt())
}

/// Only white noise on the gyro: its 120 Hz σ must be N·√120 (filters off to see it raw).
#[test]
fn gyro_white_noise_sigma_matches_density() {
    let mut cfg = SensorConfig::default();
    cfg.imu.gyro.turn_on_bias_sigma = 0.0;
    cfg.imu.gyro.in_run_bias_sigma = 0.0;
    cfg.imu.gyro.quantum = 0.0;
    cfg.imu.gyro_g_sensitivity_rps_per_mps2 = 0.0;
    cfg.imu.gyro.noise_density = 1e-3;
    cfg.imu.lag_tau_s = 0.0;
    cfg.imu.antialias_cutoff_hz = 0.0;
    let mut m = SensorModel::new(&cfg, 11);
    let x: Vec<f64> = (0..120_000)
        .map(|_| m.step(&level_input())[Channel::GyroQ.index()])
        .collect();
    let (mean, sd) = mean_std(&x);
    let want = 1e-3 * 120f64.sqrt();
    assert!((sd / want - 1.0).abs() < 0.02, "σ {sd} want {want}");
    assert!(mean.abs() < 4.0 * want / (x.len() as f64).sqrt());
}

/// Turn-on biases across many flights (seeds) have the configured σ, and a flight's mean output
/// equals its drawn bias plus the g-dependent term.
#[test]
fn turn_on_bias_and_g_sensitivity_are_measured_back() {
    let mut cfg = SensorConfig::default();
    cfg.imu.gyro.turn_on_bias_sigma = 1e-3;
    cfg.imu.gyro.in_run_bias_sigma = 0.0;
    cfg.imu.gyro.noise_density = 0.0;
    cfg.imu.gyro.quantum = 0.0;
    cfg.imu.gyro_g_sensitivity_rps_per_mps2 = 1e-4;
    let biases: Vec<f64> = (0..2000)
        .map(|seed| SensorModel::new(&cfg, seed).gyro_axes()[0].turn_on_bias())
        .collect();
    let (m, sd) = mean_std(&biases);
    assert!((sd / 1e-3 - 1.0).abs() < 0.06, "bias σ {sd}");
    assert!(m.abs() < 1e-4);

    let mut model = SensorModel::new(&cfg, 5);
    let b = model.gyro_axes()[2].turn_on_bias();
    let mut out = 0.0;
    for _ in 0..600 {
        out = model.step(&level_input())[Channel::GyroR.index()];
    }
    // z axis sees −9.80665 m/s² of specific force (lever arm adds nothing at zero rate).
    let want = b + 1e-4 * -9.80665;
    assert!((out - want).abs() < 1e-12, "{out} vs {want}");
}

/// The in-run Gauss-Markov bias has its configured steady-state σ over a long run.
#[test]
fn in_run_bias_is_gauss_markov_with_configured_sigma() {
    let mut cfg = SensorConfig::default();
    cfg.imu.accel.turn_on_bias_sigma = 0.0;
    cfg.imu.accel.noise_density = 0.0;
    cfg.imu.accel.quantum = 0.0;
    cfg.imu.accel.in_run_bias_sigma = 0.01;
    cfg.imu.accel.in_run_bias_tau_s = 1.0;
    let mut m = SensorModel::new(&cfg, 3);
    let x: Vec<f64> = (0..600_000)
        .map(|_| m.step(&level_input())[Channel::AccelX.index()])
        .collect();
    let (_, sd) = mean_std(&x);
    assert!((sd / 0.01 - 1.0).abs() < 0.1, "GM σ {sd}");
}

/// Raw IMU output comes in whole Δθ counts per step and the carried residual keeps the mean exact.
#[test]
fn quantization_step_and_residual_carry() {
    let cfg = SensorConfig::default();
    let q = 1e-3;
    let mut e = cfg.imu.gyro.clone();
    e.turn_on_bias_sigma = 0.0;
    e.in_run_bias_sigma = 0.0;
    e.noise_density = 0.0;
    e.quantum = q;
    let mut c2 = cfg.clone();
    c2.imu.gyro = e;
    c2.imu.gyro_g_sensitivity_rps_per_mps2 = 0.0;
    let mut m = SensorModel::new(&c2, 1);
    let dt = 1.0 / 120.0;
    let truth = 0.0237;
    let mut sum = 0.0;
    let mut distinct = std::collections::BTreeSet::new();
    let n = 12_000;
    for _ in 0..n {
        let raw = m.gyro_raw_for_test(0, truth);
        let counts = raw * dt / q;
        assert!(
            (counts - counts.round()).abs() < 1e-6,
            "not whole counts: {counts}"
        );
        distinct.insert(counts.round() as i64);
        sum += raw;
    }
    assert!(distinct.len() >= 2, "a rate between two counts must dither");
    assert!((sum / n as f64 - truth).abs() < 2.0 * q / dt / n as f64);
}

/// Surface sensors: quantized to their step, noise σ as configured.
#[test]
fn surface_quantum_and_noise() {
    let mut cfg = SensorConfig::default();
    cfg.surfaces.noise_sigma_deg = 0.2;
    cfg.surfaces.quantum_deg = 0.05;
    let mut m = SensorModel::new(&cfg, 9);
    let x: Vec<f64> = (0..50_000)
        .map(|_| m.step(&level_input())[Channel::Elevator.index()])
        .collect();
    for v in &x {
        assert!(((v / 0.05) - (v / 0.05).round()).abs() < 1e-9);
    }
    let (mean, sd) = mean_std(&x);
    // Quantization adds q²/12 of variance.
    let want = (0.2f64.powi(2) + 0.05f64.powi(2) / 12.0).sqrt();
    assert!((sd / want - 1.0).abs() < 0.03, "σ {sd} want {want}");
    assert!((mean + 1.234).abs() < 0.01);
}

/// GPS: a step in speed shows up after the configured latency, held at the fix rate.
#[test]
fn gps_latency_and_hold() {
    let mut cfg = SensorConfig::default();
    cfg.gps.speed_noise_sigma_mps = 0.0;
    cfg.gps.latency_s = 0.1;
    cfg.gps.update_hz = 120.0;
    let mut m = SensorModel::new(&cfg, 2);
    let mut inp = level_input();
    for _ in 0..60 {
        m.step(&inp);
    }
    inp.gps_speed_mps = 250.0;
    let mut seen = None;
    for k in 0..60 {
        if m.step(&inp)[Channel::GpsSpeed.index()] == 250.0 {
            seen = Some(k);
            break;
        }
    }
    assert_eq!(seen, Some(12), "latency 0.1 s = 12 steps at 120 Hz");
}

#[test]
fn same_seed_same_outputs_other_seed_differs() {
    let cfg = SensorConfig::default();
    let run = |seed| {
        let mut m = SensorModel::new(&cfg, seed);
        (0..500).map(|_| m.step(&level_input())).collect::<Vec<_>>()
    };
    assert_eq!(run(4), run(4));
    assert_ne!(run(4), run(5));
}

#[test]
fn bad_sensor_configs_are_rejected_with_the_field() {
    let dir = std::env::temp_dir().join(format!("hil-sensors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("bad.toml");
    std::fs::write(&p, "[gps]\nlatency_s = -1.0\n").unwrap();
    let e = SensorConfig::load(&p).unwrap_err();
    assert!(e.to_string().contains("gps.latency_s"), "{e}");
    std::fs::write(&p, "[imu]\nno_such_field = 1\n").unwrap();
    let e = SensorConfig::load(&p).unwrap_err();
    assert!(
        matches!(e, hil_sim::sensors::SensorConfigError::Parse { .. }),
        "{e}"
    );
    std::fs::write(&p, "[surfaces]\nquantum_deg = 0.1\n").unwrap();
    let c = SensorConfig::load(&p).unwrap();
    assert_eq!(c.surfaces.quantum_deg, 0.1);
    assert_eq!(c.imu, SensorConfig::default().imu);
    let e = SensorConfig::load(&dir.join("missing.toml")).unwrap_err();
    assert!(matches!(
        e,
        hil_sim::sensors::SensorConfigError::Read { .. }
    ));
    std::fs::remove_dir_all(&dir).ok();
}
