//! `trainer eval-filter --frames`: the air-data filter's force model against the normal force the
//! IMU measures, frame by frame (scripts/analysis/force-residual).

mod common;

use trainer::filter_eval::force_frames;

#[test]
fn on_its_own_aircraft_the_force_model_at_the_true_point_explains_the_measured_normal_force() {
    let f = common::first_150_s_of_the_test_flight();
    let frames: Vec<_> = hil_sim::frames::flight_frames(&f).collect();
    let truth: Vec<_> = f.samples.iter().map(|s| s.truth).collect();
    let cfg = estimator_core::filter::CONFIG;
    // One truth record per frame, or a refusal.
    assert!(force_frames(cfg, &frames, &truth[1..]).is_err());
    let rows = force_frames(cfg, &frames, &truth).expect("one truth record per frame");
    assert_eq!(rows.len(), frames.len());
    // The first frame has no previous one to move the IMU's force to the CG with.
    assert!(rows[0].fz_measured.is_nan() && rows[0].fz_model_true.is_nan());
    let both: Vec<_> = rows
        .iter()
        .filter(|r| r.fz_measured.is_finite() && r.fz_model_true.is_finite())
        .collect();
    assert!(
        both.len() + 1 == rows.len(),
        "{} of {}",
        both.len(),
        rows.len()
    );
    let n = both.len() as f64;
    let res: Vec<f64> = both
        .iter()
        .map(|r| r.fz_measured - r.fz_model_true)
        .collect();
    let mean = res.iter().sum::<f64>() / n;
    let rms = (res.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let mean_fz = both.iter().map(|r| r.fz_measured).sum::<f64>() / n;
    eprintln!("residual mean {mean:+.4} rms {rms:.4} m/s², mean measured {mean_fz:+.3}");
    // The model is the plant's own: no bias (a lift 1 % off the plant's would leave 0.1 m/s²), and
    // what scatters is the measurement chain in the manoeuvres (the IMU's filtering against the
    // instant the truth is sampled at, the sensed surfaces), well under a tenth of the load.
    assert!(
        mean_fz < -9.0,
        "the first 150 s hold at least 1 g on average: {mean_fz}"
    );
    assert!(mean.abs() < 0.05, "mean {mean}");
    assert!(rms < 0.1 * mean_fz.abs(), "rms {rms}");
    // More α, more lift: the normal force (body z, down positive) falls with α wherever the filter
    // has an estimate, and at its own point the model gives the measured force within the force the
    // filter allows its model (`filter.accel_sigma_mps2`) on average.
    let at_filter: Vec<_> = rows
        .iter()
        .filter(|r| r.filter_clear && r.dfz_dalpha_filter.is_finite())
        .collect();
    assert!(at_filter.len() as f64 > 0.9 * n);
    assert!(at_filter.iter().all(|r| r.dfz_dalpha_filter < 0.0));
    let off = at_filter
        .iter()
        .map(|r| (r.fz_measured - r.fz_model_filter).abs())
        .sum::<f64>()
        / at_filter.len() as f64;
    eprintln!("at the filter's point: mean |measured − model| {off:.4} m/s²");
    let allowed = f64::from(estimator_core::filter::CONFIG.accel_sigma[1]);
    assert!(
        off < allowed,
        "the filter's point misses the force by {off} m/s² on average (it allows {allowed})"
    );
}
