//! Sensor error models measured back from long samples (no JSBSim needed).
//!
//! The statistics tests run the DEFAULT configuration (no inflated errors) on synthetic level
//! flight: specific force (0, 0, −g) at the CG and body rates equal to the Earth's rotation, as the
//! plant feeds them (inertial rates). Each tolerance is about 4 standard errors of its estimator,
//! stated where it is computed; every random draw is seeded, so a run is repeatable.

use estimator_core::Channel;
use hil_sim::sensors::{SensorConfig, SensorInput, SensorModel, specific_force_at};

const DT: f64 = 1.0 / 120.0;
const G0: f64 = 9.80665;
/// WGS-84 Earth rotation rate, rad/s.
const EARTH_RATE_RPS: f64 = 7.292115e-5;
const DEG_PER_H: f64 = std::f64::consts::PI / 180.0 / 3600.0;

fn level_input() -> SensorInput {
    SensorInput {
        f_cg_mps2: [0.0, 0.0, -9.80665],
        gps_speed_mps: 200.0,
        alt_msl_m: 5000.0,
        // The elevator (first of `SURFACE_CHANNELS`) off neutral; the other surfaces at 0.
        surfaces_deg: [-1.234, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        throttle_norm: 0.4321,
        ..SensorInput::default()
    }
}

/// Body rates of a level, unaccelerated aircraft at latitude 45°, true heading 30°: only the Earth's
/// rotation, Ω·(cos φ, 0, −sin φ) in north-east-down axes, turned into body axes by the heading, so
/// all three gyros see a part of it.
fn earth_rate_body() -> [f64; 3] {
    let (lat, heading) = (45f64.to_radians(), 30f64.to_radians());
    let north = EARTH_RATE_RPS * lat.cos();
    let down = -EARTH_RATE_RPS * lat.sin();
    [north * heading.cos(), -north * heading.sin(), down]
}

/// Level flight as the gyros see it: inertial body rates = Earth rate.
fn level_flight() -> SensorInput {
    SensorInput {
        omega_rps: earth_rate_body(),
        ..level_input()
    }
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, var.sqrt())
}

/// RMS about zero: the σ estimate for draws whose mean is known to be 0 (n degrees of freedom).
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// Overlapping Allan variance of rate samples `y` (spacing DT) at τ = m·DT, from the integrated
/// signal θ (mean removed first, so θ stays small): Σ (θ[k+2m] − 2θ[k+m] + θ[k])² / (2τ²(N − 2m)),
/// N = number of θ points.
fn allan_var(y: &[f64], m: usize) -> f64 {
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let mut theta = Vec::with_capacity(y.len() + 1);
    let mut acc = 0.0;
    theta.push(acc);
    for v in y {
        acc += (v - mean) * DT;
        theta.push(acc);
    }
    let terms = theta.len() - 2 * m;
    let sum: f64 = (0..terms)
        .map(|k| {
            let d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
            d * d
        })
        .sum();
    let tau = m as f64 * DT;
    sum / (2.0 * tau * tau * terms as f64)
}

/// Equivalent degrees of freedom of the overlapping Allan variance of white rate noise with `n`
/// θ points at τ = m·τ0 (NIST SP 1065, Riley 2008, §5.3 "white FM"); σ̂/σ then has a relative
/// standard deviation of 1/√(2·edf).
fn allan_edf_white(n: usize, m: usize) -> f64 {
    let (n, m) = (n as f64, m as f64);
    (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * 4.0 * m * m / (4.0 * m * m + 5.0)
}

/// Allan variance of a first-order Gauss-Markov process per unit σ²: (T/τ)·[2 − (T/τ)·(3 −
/// 4e^(−τ/T) + e^(−2τ/T))], T the correlation time (≈ 2τ/(3T) for τ ≪ T, 2T/τ for τ ≫ T).
fn gauss_markov_allan_shape(tau_s: f64, corr_s: f64) -> f64 {
    let r = corr_s / tau_s;
    let x = tau_s / corr_s;
    r * (2.0 - r * (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()))
}

/// Turn-on biases of the default configuration across 2000 flights (seeds): 6000 draws per
/// sensor type, so σ̂ (RMS about the known zero mean) has a relative standard error of
/// 1/√(2·6000) = 0.9 %; the tolerance is 4× that.
#[test]
fn turn_on_bias_sigma_over_2000_flights() {
    let cfg = SensorConfig::default();
    let (mut gyro, mut accel) = (Vec::new(), Vec::new());
    for seed in 0..2000 {
        let m = SensorModel::new(&cfg, seed);
        for k in 0..3 {
            gyro.push(m.gyro_axes()[k].turn_on_bias());
            accel.push(m.accel_axes()[k].turn_on_bias());
        }
    }
    let tol = 4.0 / (2.0 * gyro.len() as f64).sqrt();
    for (name, draws, want) in [
        ("gyro", &gyro, cfg.imu.gyro.turn_on_bias_sigma),
        ("accel", &accel, cfg.imu.accel.turn_on_bias_sigma),
    ] {
        let sd = rms(draws);
        eprintln!(
            "{name} turn-on bias σ: measured {sd:.4e}, configured {want:.4e} (ratio {:.4}, tol ±{tol:.4})",
            sd / want
        );
        assert!(
            (sd / want - 1.0).abs() < tol,
            "{name} turn-on σ {sd} vs {want}"
        );
    }
}

/// ARW, VRW and the accelerometer in-run bias from the overlapping Allan deviation of the raw
/// 120 Hz output, default configuration, 16 flights × 1 h of level flight, three axes each (48
/// records per sensor type, averaged).
///
/// White noise is read where it dominates, σ_A(τ) = N/√τ:
/// - gyro at τ = 1 s: the Δθ quantization (residual carried, so the angle error is bounded by
///   Q/2) adds Q²/(4τ²) = 0.2 % of the white variance, the in-run bias (≈ 2σ_b²τ/(3T) for τ ≪ T)
///   0.005 %;
/// - accel at τ = 0.25 s: the in-run bias (50 µg, 60 s) adds 0.03 %, quantization less.
///
/// Tolerance 4/√(2·edf) with edf the white-noise EDF of the overlapping estimator summed over the
/// records. The accel in-run bias is read at τ = 2T = 120 s, near the top of its Allan curve, where
/// it is 98 % of the variance: σ_b² = (σ_A² − N̂²/τ) / shape(τ, T), with its standard error taken
/// from the spread of the 48 per-record estimates. (The default gyro in-run bias, 0.35 °/h over
/// 100 s, stays below the 0.07 °/√h ARW at every τ — at its Allan peak it is a third of the
/// variance — so an hour-scale record cannot separate it; the same Gauss-Markov code is checked on
/// the accelerometers here and with a large σ in `in_run_bias_is_gauss_markov_with_configured_sigma`.)
#[test]
fn allan_deviation_recovers_arw_vrw_and_accel_in_run_bias() {
    let cfg = SensorConfig::default();
    let steps = 3600 * 120;
    let (m_gyro, m_accel, m_gm) = (120, 30, 120 * 120);
    let (mut av_gyro, mut av_accel, mut av_gm) = (Vec::new(), Vec::new(), Vec::new());
    let input = level_flight();
    for seed in 100..116 {
        let mut model = SensorModel::new(&cfg, seed);
        let mut rec: Vec<Vec<f64>> = (0..6).map(|_| Vec::with_capacity(steps)).collect();
        for _ in 0..steps {
            let raw = model.imu_raw_for_test(&input);
            for (r, v) in rec.iter_mut().zip(raw) {
                r.push(v);
            }
        }
        for k in 0..3 {
            av_gyro.push(allan_var(&rec[k], m_gyro));
            av_accel.push(allan_var(&rec[3 + k], m_accel));
            av_gm.push(allan_var(&rec[3 + k], m_gm));
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let records = av_gyro.len() as f64;

    for (name, av, m, want) in [
        ("gyro ARW", &av_gyro, m_gyro, cfg.imu.gyro.noise_density),
        ("accel VRW", &av_accel, m_accel, cfg.imu.accel.noise_density),
    ] {
        let tau = m as f64 * DT;
        let n_hat = (mean(av) * tau).sqrt();
        let tol = 4.0 / (2.0 * records * allan_edf_white(steps + 1, m)).sqrt();
        eprintln!(
            "{name}: σ_A({tau} s)·√τ = {n_hat:.4e}, configured {want:.4e} (ratio {:.4}, tol ±{tol:.4})",
            n_hat / want
        );
        assert!((n_hat / want - 1.0).abs() < tol, "{name} {n_hat} vs {want}");
    }

    let e = &cfg.imu.accel;
    let tau = m_gm as f64 * DT;
    let n_hat_sq = mean(&av_accel) * m_accel as f64 * DT;
    let shape = gauss_markov_allan_shape(tau, e.in_run_bias_tau_s);
    let per_record: Vec<f64> = av_gm.iter().map(|a| (a - n_hat_sq / tau) / shape).collect();
    let (var_hat, sd) = mean_std(&per_record);
    let se = sd / records.sqrt();
    let want = e.in_run_bias_sigma.powi(2);
    eprintln!(
        "accel in-run bias: σ_b = {:.4e} (from σ_A({tau} s)), configured {:.4e} (ratio {:.4}); \
         σ_b² standard error {:.1} %",
        var_hat.sqrt(),
        e.in_run_bias_sigma,
        var_hat.sqrt() / e.in_run_bias_sigma,
        100.0 * se / want
    );
    // The spread itself must be small enough for the check to mean something: with SE < 6 %,
    // 4 SE keeps σ_b within about ±12 %.
    assert!(se < 0.06 * want, "σ_b² standard error {se} too large");
    assert!(
        (var_hat - want).abs() < 4.0 * se,
        "σ_b² {var_hat} vs {want} (SE {se})"
    );
}

/// A flight's mean output is its drawn turn-on bias plus the g-dependent term (noise, in-run bias
/// and quantization off, so the check is exact).
#[test]
fn turn_on_bias_and_g_sensitivity_add_to_the_output() {
    let mut cfg = SensorConfig::default();
    cfg.imu.gyro.turn_on_bias_sigma = 1e-3;
    cfg.imu.gyro.in_run_bias_sigma = 0.0;
    cfg.imu.gyro.noise_density = 0.0;
    cfg.imu.gyro.quantum = 0.0;
    cfg.imu.gyro_g_sensitivity_rps_per_mps2 = 1e-4;
    let mut model = SensorModel::new(&cfg, 5);
    let b = model.gyro_axes()[2].turn_on_bias();
    assert!(b != 0.0);
    let mut out = 0.0;
    for _ in 0..600 {
        out = model.step(&level_input())[Channel::GyroR.index()];
    }
    // z axis sees −9.80665 m/s² of specific force (lever arm adds nothing at zero rate).
    let want = b + 1e-4 * -9.80665;
    assert!((out - want).abs() < 1e-12, "{out} vs {want}");
}

/// A level flight's mean gyro output (full path: lag and anti-alias filter have unit DC gain) is
/// the Earth rate through the flight's scale-factor/misalignment matrix, plus its turn-on bias and
/// g term: the model passes the inertial rate it is given through. Over L = 2400 s the mean of the
/// in-run bias has σ ≈ σ_b·√(2T/L) and of the white noise N/√L, together ≈ 0.14 °/h; the tolerance
/// is 4× that, far below the 5–11 °/h Earth-rate components, so dropping them would fail.
#[test]
fn earth_rate_passes_through_to_the_gyros() {
    let cfg = SensorConfig::default();
    let mut model = SensorModel::new(&cfg, 21);
    let input = level_flight();
    let steps = 2400 * 120;
    let mut sum = [0.0; 3];
    for _ in 0..steps {
        let out = model.step(&input);
        for (k, s) in sum.iter_mut().enumerate() {
            *s += out[Channel::GyroP.index() + k];
        }
    }
    let e = &cfg.imu.gyro;
    let l = steps as f64 * DT;
    let tol = 4.0
        * (2.0 * e.in_run_bias_sigma.powi(2) * e.in_run_bias_tau_s / l
            + e.noise_density.powi(2) / l)
            .sqrt();
    let w = input.omega_rps;
    let f_imu = specific_force_at(
        input.f_cg_mps2,
        w,
        input.omega_dot_rps2,
        cfg.imu.lever_arm_m,
    );
    let em = model.gyro_scale_misalignment();
    for k in 0..3 {
        let sensed = w[k] + em[k][0] * w[0] + em[k][1] * w[1] + em[k][2] * w[2];
        let want = sensed
            + model.gyro_axes()[k].turn_on_bias()
            + cfg.imu.gyro_g_sensitivity_rps_per_mps2 * f_imu[k];
        let got = sum[k] / steps as f64;
        eprintln!(
            "gyro {k}: mean {:.3} °/h, Earth rate {:.3} °/h, expected {:.3} °/h (tol ±{:.3})",
            got / DEG_PER_H,
            w[k] / DEG_PER_H,
            want / DEG_PER_H,
            tol / DEG_PER_H
        );
        assert!(w[k].abs() > 10.0 * tol, "test cannot see the Earth rate");
        assert!((got - want).abs() < tol, "axis {k}: {got} vs {want}");
    }
}

/// Scale factor and misalignment, default configuration, 500 flights. Per flight and input axis j,
/// the truth is level flight plus steps on axis j of +1, −1, −2, +2, +2, −2, −1, +1 (rad/s for the
/// gyros, g of specific force for the accelerometers), 1 s each: symmetric in time, so a slow drift
/// of the in-run bias does not project on the slope, and odd in level, so the even centripetal and
/// g-sensitivity terms do not either. The slope of output axis i against the level is δ_ij + E_ij.
///
/// Per flight, the estimate must match the drawn E (accessor): the standard error of a slope is the
/// white noise of a 1 s mean over √Σ(level²) = √20 units, 4.6e-6 (gyro) and 1.1e-5 (accel) — 2–6 %
/// of the configured σ; the RMS error over all flights must be within 1.5× of that (the
/// accelerometer in-run bias adds a little), the worst within 6×. Across flights, σ̂ (RMS about the
/// known zero mean, with the small estimation variance subtracted) of 1500 scale factors and 3000
/// misalignment angles per sensor type must match the configured σ within 4/√(2n): 7.3 % and 5.2 %.
#[test]
fn scale_factor_and_misalignment_are_recovered_per_flight_and_across_flights() {
    let cfg = SensorConfig::default();
    let levels = [1.0, -1.0, -2.0, 2.0, 2.0, -2.0, -1.0, 1.0];
    let sxx: f64 = levels.iter().map(|l: &f64| l * l).sum();
    let hold = 120;
    let base = level_flight();
    for (name, unit, sens, slope_se) in [
        (
            "gyro",
            1.0,
            &cfg.imu.gyro,
            cfg.imu.gyro.noise_density / sxx.sqrt(),
        ),
        (
            "accel",
            G0,
            &cfg.imu.accel,
            cfg.imu.accel.noise_density / (G0 * sxx.sqrt()),
        ),
    ] {
        let is_gyro = name == "gyro";
        let (mut sf, mut mis, mut err) = (Vec::new(), Vec::new(), Vec::new());
        let mut worst: f64 = 0.0;
        for seed in 0..500u64 {
            let mut model = SensorModel::new(&cfg, 1000 + seed);
            let drawn = if is_gyro {
                model.gyro_scale_misalignment()
            } else {
                model.accel_scale_misalignment()
            };
            for j in 0..3 {
                let mut sxy = [0.0; 3];
                for &l in &levels {
                    let mut input = base;
                    if is_gyro {
                        input.omega_rps[j] += l * unit;
                    } else {
                        input.f_cg_mps2[j] += l * unit;
                    }
                    let mut sum = [0.0; 3];
                    for _ in 0..hold {
                        let raw = model.imu_raw_for_test(&input);
                        let out = if is_gyro { &raw[..3] } else { &raw[3..] };
                        for (s, v) in sum.iter_mut().zip(out) {
                            *s += v;
                        }
                    }
                    // Levels sum to zero, so Σ l·ȳ is the centred cross product.
                    for (c, s) in sxy.iter_mut().zip(sum) {
                        *c += l * s / hold as f64;
                    }
                }
                for (i, (c, row)) in sxy.iter().zip(&drawn).enumerate() {
                    let slope = c / (sxx * unit);
                    let e_hat = slope - if i == j { 1.0 } else { 0.0 };
                    let d = e_hat - row[j];
                    err.push(d);
                    worst = worst.max(d.abs());
                    if i == j {
                        sf.push(e_hat)
                    } else {
                        mis.push(e_hat)
                    }
                }
            }
        }
        let err_rms = rms(&err);
        eprintln!(
            "{name}: per-flight error RMS {err_rms:.3e}, worst {worst:.3e}, predicted SE {slope_se:.3e}"
        );
        assert!(
            err_rms < 1.5 * slope_se,
            "{name} per-flight RMS error {err_rms}"
        );
        assert!(
            worst < 6.0 * slope_se,
            "{name} worst per-flight error {worst}"
        );
        for (what, v, want) in [
            ("scale factor", &sf, sens.scale_factor_sigma),
            ("misalignment", &mis, sens.misalignment_sigma_rad),
        ] {
            let n = v.len() as f64;
            let sd = (rms(v).powi(2) - err_rms.powi(2)).max(0.0).sqrt();
            let tol = 4.0 / (2.0 * n).sqrt();
            let (m, _) = mean_std(v);
            eprintln!(
                "{name} {what} σ: measured {sd:.4e}, configured {want:.4e} (ratio {:.4}, tol ±{tol:.4}), mean {m:.2e}",
                sd / want
            );
            assert!(
                (sd / want - 1.0).abs() < tol,
                "{name} {what} σ {sd} vs {want}"
            );
            assert!(m.abs() < 4.0 * want / n.sqrt(), "{name} {what} mean {m}");
        }
    }
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
    std::fs::write(&p, "[imu.accel]\nmisalignment_sigma_rad = -1e-4\n").unwrap();
    let e = SensorConfig::load(&p).unwrap_err();
    assert!(
        e.to_string().contains("imu.accel.misalignment_sigma_rad"),
        "a partial table parses, and its negative σ is refused by name: {e}"
    );
    std::fs::write(
        &p,
        "[imu.gyro]\nturn_on_bias_sigma = 0.0\nin_run_bias_sigma = 0.0\nin_run_bias_tau_s = 1.0\n\
         noise_density = 0.0\nquantum = 0.0\nscale_factor_sigma = -1e-4\n",
    )
    .unwrap();
    let e = SensorConfig::load(&p).unwrap_err();
    assert!(e.to_string().contains("imu.gyro.scale_factor_sigma"), "{e}");
    // A partial table parses; the fields it leaves out take the built-in gyro's values.
    std::fs::write(
        &p,
        "[imu.gyro]\nturn_on_bias_sigma = 4.8e-5\nin_run_bias_sigma = 1.7e-6\n\
         in_run_bias_tau_s = 100.0\nnoise_density = 2.0e-5\nquantum = 1.9e-6\n",
    )
    .unwrap();
    let c = SensorConfig::load(&p).unwrap();
    assert_eq!(c.imu.gyro.turn_on_bias_sigma, 4.8e-5);
    let gyro = SensorConfig::default().imu.gyro;
    assert_eq!(c.imu.gyro.scale_factor_sigma, gyro.scale_factor_sigma);
    assert_eq!(
        c.imu.gyro.misalignment_sigma_rad,
        gyro.misalignment_sigma_rad
    );
    assert_eq!(c.imu.accel, SensorConfig::default().imu.accel);
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
