//! Behaviour of `Estimator::step` on bad input, with a small fixed network (a test fixture, not a
//! trained model): α reads the GPS speed and the elevator, β reads the rudder and the roll gyro.

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::arithmetic_side_effects
)]

use estimator_core::channels::{ALL_VALID, CHANNELS};
use estimator_core::estimator::STUCK_FRAMES;
use estimator_core::nn::{Chain, Dense, Hidden, Output, Requant};
use estimator_core::normalize::{Envelope, Norm, TurbulenceEnvelope};
use estimator_core::{AngleNet, CascadeNet, Channel, Estimator, Feature, Flags, Lag, SensorFrame};

type Part1 = Chain<Hidden<2, 3>, Output<3, 1>, 3>;
type Part2 = Chain<Hidden<3, 2>, Output<2, 1>, 2>;

const RQ: Requant = Requant {
    mult: 1 << 20,
    shift: 24,
    offset: 0,
};

fn net(a: Channel, b: Channel, env_hi: i32) -> CascadeNet<Part1, Part2, 2, 3> {
    net_of(Feature::Sensor(a), Feature::Sensor(b), env_hi)
}

fn net_of(a: Feature, b: Feature, env_hi: i32) -> CascadeNet<Part1, Part2, 2, 3> {
    CascadeNet {
        features: [a, b],
        norm: [Norm {
            center: 0,
            mult: 1,
            shift: 4,
        }; 2],
        envelope: [Envelope {
            lo: -env_hi,
            hi: env_hi,
        }; 2],
        part1: Chain(
            Hidden(Dense::new(
                [[10, 20], [30, -40], [5, 5]],
                [100, 0, -100],
                [RQ; 3],
            )),
            Output(Dense::new([[1, 2, 3]], [7], [Requant::ONE])),
        ),
        mid_norm: Norm {
            center: 0,
            mult: 1,
            shift: 2,
        },
        part2: Chain(
            Hidden(Dense::new([[3, -2, 1], [1, 1, 1]], [0, 50], [RQ; 2])),
            Output(Dense::new(
                [[4, -5]],
                [1000],
                [Requant {
                    mult: 1 << 30,
                    shift: 30,
                    offset: 250,
                }],
            )),
        ),
        out_range: Envelope {
            lo: -90_000,
            hi: 90_000,
        },
        turbulence: TurbulenceEnvelope::ANY,
        lift_scale: Envelope::ANY,
    }
}

fn nets() -> (
    CascadeNet<Part1, Part2, 2, 3>,
    CascadeNet<Part1, Part2, 2, 3>,
) {
    (
        net(Channel::GpsSpeed, Channel::Elevator, 400_000),
        net(Channel::Rudder, Channel::GyroP, 400_000),
    )
}

fn frame(seq: u16) -> SensorFrame {
    let mut raw = [0i32; CHANNELS];
    for (i, r) in raw.iter_mut().enumerate() {
        // Noisy channels change every frame; surfaces are constant.
        *r = if Channel::ALL[i].is_noisy() {
            1000 * i as i32 + (seq as i32 % 7) * 13
        } else {
            150 * i as i32
        };
    }
    raw[Channel::GpsSpeed.index()] = 200_000 + seq as i32;
    SensorFrame {
        seq,
        time_ms: seq as u32 * 50,
        raw,
        valid: ALL_VALID,
        sub: estimator_core::channels::Subsamples::NONE,
    }
}

/// The flags without `UNCERTAIN`: the toy networks here get the shipped 1σ weights, fitted for
/// other networks, so whether their 1σ crosses the limit says nothing about the input checks.
fn input_flags(f: Flags) -> Flags {
    Flags(f.0 & !Flags::UNCERTAIN)
}

#[test]
fn good_frames_give_live_estimates_without_flags() {
    let (a, b) = nets();
    let mut e = Estimator::new(&a, &b);
    for s in 0..50 {
        let out = e.step(&frame(s));
        assert_eq!(input_flags(out.flags), Flags(0), "frame {s}: {out:?}");
        assert_eq!(out.seq, s);
    }
    assert_eq!(e.macs(), 2 * (2 * 3 + 3 + 3 * 2 + 2));
}

#[test]
fn same_frames_give_same_estimates() {
    let (a, b) = nets();
    let (mut e1, mut e2) = (Estimator::new(&a, &b), Estimator::new(&a, &b));
    for s in 0..30 {
        assert_eq!(e1.step(&frame(s)), e2.step(&frame(s)));
    }
}

#[test]
fn invalid_channel_holds_only_the_angle_that_uses_it() {
    let (a, b) = nets();
    let mut e = Estimator::new(&a, &b);
    let good = e.step(&frame(1));
    let mut bad = frame(2);
    bad.valid &= !Channel::Rudder.bit();
    let out = e.step(&bad);
    assert!(out.flags.has(Flags::INVALID_INPUT));
    assert!(out.flags.has(Flags::BETA_HELD));
    assert!(!out.flags.has(Flags::ALPHA_HELD));
    assert_eq!(out.beta_mdeg, good.beta_mdeg);
    assert_eq!(out.v_aero_mms, good.v_aero_mms);
    assert!(!out.flags.is_usable());
}

#[test]
fn invalid_before_any_good_frame_gives_zero_and_no_estimate() {
    let (a, b) = nets();
    let mut e = Estimator::new(&a, &b);
    let si = [f64::NAN; CHANNELS];
    let out = e.step(&SensorFrame::from_si(0, 0, &si));
    assert!(out.flags.has(Flags::NO_ESTIMATE | Flags::INVALID_INPUT));
    assert_eq!(
        (
            out.alpha_mdeg,
            out.beta_mdeg,
            out.w_aero_mms,
            out.v_aero_mms
        ),
        (0, 0, 0, 0)
    );
}

#[test]
fn a_stuck_gyro_is_detected_after_stuck_frames_and_recovers() {
    let (a, b) = nets();
    let mut e = Estimator::new(&a, &b);
    let mut flagged_at = None;
    for s in 0..(STUCK_FRAMES + 5) {
        let mut f = frame(s);
        f.raw[Channel::GyroP.index()] = 4242;
        let out = e.step(&f);
        if out.flags.has(Flags::STUCK_SENSOR) && flagged_at.is_none() {
            flagged_at = Some(s);
            assert!(out.flags.has(Flags::BETA_HELD));
            assert!(!out.flags.has(Flags::ALPHA_HELD));
        }
    }
    assert_eq!(flagged_at, Some(STUCK_FRAMES - 1));
    let out = e.step(&frame(100));
    assert!(!out.flags.has(Flags::STUCK_SENSOR));
}

#[test]
fn a_gyro_at_full_scale_holds_beta_on_that_frame_and_releases_it_on_the_next() {
    let (a, b) = nets();
    let mut e = Estimator::new(&a, &b);
    let good = e.step(&frame(0));
    for fs in [17_453_293, -17_453_293, i32::MAX] {
        let mut f = frame(1);
        f.raw[Channel::GyroP.index()] = fs;
        let out = e.step(&f);
        assert!(out.flags.has(Flags::SATURATED | Flags::BETA_HELD), "{fs}");
        assert!(
            !out.flags.has(Flags::ALPHA_HELD | Flags::INVALID_INPUT),
            "{fs}"
        );
        assert_eq!(out.beta_mdeg, good.beta_mdeg);
    }
    let mut f = frame(2);
    f.raw[Channel::GyroP.index()] = 17_453_292;
    assert_eq!(
        e.step(&f).flags.0 & (Flags::SATURATED | Flags::BETA_HELD),
        0
    );
}

/// The repeat count saturates at u16::MAX (55 minutes at 20 Hz); the sensor must stay stuck past
/// it. (The flight image once wrapped `count + 1` to 0 there and cleared the flag for good.)
#[test]
fn a_sensor_stuck_for_an_hour_stays_stuck() {
    let (a, b) = nets();
    let mut e = Estimator::new(&a, &b);
    for k in 0..u32::from(u16::MAX) + 100 {
        let mut f = frame(k as u16);
        f.time_ms = k * 50;
        f.raw[Channel::GyroP.index()] = 4242;
        let out = e.step(&f);
        if k + 1 >= u32::from(STUCK_FRAMES) {
            assert!(out.flags.has(Flags::STUCK_SENSOR), "frame {k}");
        }
    }
}

#[test]
fn out_of_envelope_inputs_are_clamped_and_flagged() {
    let (a, b) = nets();
    let mut e = Estimator::new(&a, &b);
    let mut f = frame(3);
    f.raw[Channel::Elevator.index()] = 500_000;
    let out = e.step(&f);
    assert!(out.flags.has(Flags::OUT_OF_ENVELOPE));
    assert!(!out.flags.has(Flags::ALPHA_HELD));
    let mut g = frame(3);
    g.raw[Channel::Elevator.index()] = 400_000; // exactly the envelope edge
    let mut e2 = Estimator::new(&a, &b);
    assert_eq!(e.step(&f).alpha_mdeg, e2.step(&g).alpha_mdeg);
}

#[test]
fn extreme_raw_values_never_panic() {
    let (a, b) = nets();
    let mut e = Estimator::new(&a, &b);
    // Per angle, how many computed frames ago its 1σ was last above its limit.
    let mut since_above: [Option<u32>; 2] = [None; 2];
    for (s, v) in [i32::MIN, i32::MAX, 0, -1, 1].into_iter().enumerate() {
        let f = SensorFrame {
            seq: s as u16,
            time_ms: 0,
            raw: [v; CHANNELS],
            valid: u32::MAX,
            sub: estimator_core::channels::Subsamples::NONE,
        };
        let out = e.step(&f);
        assert!(out.alpha_mdeg.abs() <= 90_000);
        // Every 1σ is a defined value: none for a held angle, at most SIGMA_MAX otherwise.
        for (held, sigma) in [
            (Flags::ALPHA_HELD, out.sigma_alpha_mdeg),
            (Flags::BETA_HELD, out.sigma_beta_mdeg),
        ] {
            let unknown = estimator_core::uncertainty::SIGMA_UNKNOWN;
            assert_eq!(out.flags.has(held), sigma == unknown, "{out:?}");
        }
        // UNCERTAIN says exactly that a computed angle's 1σ is above its limit, or was within
        // that angle's last UNCERTAIN_HOLD_FRAMES computed frames.
        let mut expected = false;
        for ((held, sigma, limit), since) in [
            (
                Flags::ALPHA_HELD,
                out.sigma_alpha_mdeg,
                estimator_core::UNCERTAIN_ALPHA_MDEG,
            ),
            (
                Flags::BETA_HELD,
                out.sigma_beta_mdeg,
                estimator_core::UNCERTAIN_BETA_MDEG,
            ),
        ]
        .into_iter()
        .zip(since_above.iter_mut())
        {
            if out.flags.has(held) {
                continue;
            }
            *since = if sigma > limit {
                Some(0)
            } else {
                since.map(|n| n + 1)
            };
            expected |=
                since.is_some_and(|n| n <= u32::from(estimator_core::UNCERTAIN_HOLD_FRAMES));
        }
        assert_eq!(out.flags.has(Flags::UNCERTAIN), expected, "{out:?}");
    }
}

#[test]
fn sources_cover_derived_features() {
    let n = net(Channel::GpsSpeed, Channel::Elevator, 1);
    assert_eq!(
        n.sources(),
        Channel::GpsSpeed.bit() | Channel::Elevator.bit()
    );
    assert_eq!(
        Feature::FzOverRhoV2.sources(),
        Channel::GpsSpeed.bit() | Channel::GpsAlt.bit() | Channel::AccelZ.bit()
    );
}

#[test]
fn short_history_is_flagged_only_for_the_angle_that_uses_deltas() {
    // α reads the 200 ms change of the elevator; β reads no delta.
    let a = net_of(
        Feature::Sensor(Channel::GpsSpeed),
        Feature::Delta(Channel::Elevator, Lag::F4),
        400_000,
    );
    let b = net(Channel::Rudder, Channel::GyroP, 400_000);
    let mut e = Estimator::new(&a, &b);
    let short = |e: &mut Estimator, s: u16| e.step(&frame(s)).flags.has(Flags::HISTORY_SHORT);
    // Frames 0-3 have no frame 200 ms back; from frame 4 on they do.
    for s in 0..4 {
        assert!(short(&mut e, s), "frame {s}");
    }
    for s in 4..10 {
        assert!(!short(&mut e, s), "frame {s}");
    }
    // Frame 10 is lost: frame 14 misses its lagged frame and is flagged, but still computed.
    for s in 11..14 {
        assert!(!short(&mut e, s), "frame {s}");
    }
    let out = e.step(&frame(14));
    assert!(out.flags.has(Flags::HISTORY_SHORT));
    assert!(out.flags.is_usable());
    assert!(!short(&mut e, 15));
    // A reset forgets the history.
    e.reset();
    assert!(short(&mut e, 16));
    // Models that read no delta feature are never flagged, even on the first frame.
    let mut e2 = Estimator::new(&b, &b);
    assert!(!short(&mut e2, 0));
}

/// `frame(seq)` with EGI values a kinematic feature can use: level, heading east at 200 m/s.
fn egi_frame(seq: u16, v_east_mms: i32) -> SensorFrame {
    let mut f = frame(seq);
    f.raw[Channel::Roll.index()] = 1_000 + i32::from(seq % 7);
    f.raw[Channel::Pitch.index()] = 40_000 + i32::from(seq % 5);
    f.raw[Channel::Heading.index()] = 1_570_796;
    f.raw[Channel::VelNorth.index()] = 3 * i32::from(seq % 11);
    f.raw[Channel::VelEast.index()] = v_east_mms + i32::from(seq % 3);
    f.raw[Channel::VelDown.index()] = 100 + i32::from(seq % 13);
    f.raw[Channel::Fuel.index()] = 20_000;
    f
}

#[test]
fn a_model_reading_egi_channels_is_held_on_table1_frames() {
    // α reads the kinematic angle of attack (EGI suite); β reads Table 1 channels only.
    let a = net_of(
        Feature::AlphaKin,
        Feature::Sensor(Channel::Elevator),
        400_000_000,
    );
    let b = net(Channel::Rudder, Channel::GyroP, 400_000);
    assert_ne!(a.sources() & !estimator_core::Suite::Table1.channels(), 0);
    let mut e = Estimator::new(&a, &b);
    // EGI frames: both live.
    for s in 0..5 {
        let out = e.step(&egi_frame(s, 200_000));
        assert_eq!(input_flags(out.flags), Flags::default(), "frame {s}");
    }
    // The same frames as a Table 1 sender delivers them: α is held (the channel is absent, an
    // invalid input), β stays live.
    let t1 = egi_frame(5, 200_000).restricted_to(estimator_core::Suite::Table1);
    let out = e.step(&t1);
    assert!(out.flags.has(Flags::INVALID_INPUT | Flags::ALPHA_HELD));
    assert!(!out.flags.has(Flags::BETA_HELD));
    // From a fresh start there is nothing to hold.
    let mut fresh = Estimator::new(&a, &b);
    let out = fresh.step(&t1);
    assert!(
        out.flags
            .has(Flags::INVALID_INPUT | Flags::ALPHA_HELD | Flags::NO_ESTIMATE)
    );
    assert_eq!((out.alpha_mdeg, out.w_aero_mms), (0, 0));
    // A held or missing angle has no 1σ; the live one has one.
    assert_eq!(
        out.sigma_alpha_mdeg,
        estimator_core::uncertainty::SIGMA_UNKNOWN
    );
    assert!(out.sigma_beta_mdeg < estimator_core::uncertainty::SIGMA_UNKNOWN);
    assert_eq!(
        fresh.sigma_terms()[0],
        [0; estimator_core::uncertainty::TERMS]
    );
}

#[test]
fn low_ground_speed_flags_only_models_reading_the_egi_velocity() {
    let a = net_of(
        Feature::AlphaKin,
        Feature::Sensor(Channel::Elevator),
        400_000_000,
    );
    let b = net(Channel::Rudder, Channel::GyroP, 400_000);
    let mut e = Estimator::new(&a, &b);
    let out = e.step(&egi_frame(0, 5_000));
    assert!(out.flags.has(Flags::OUT_OF_ENVELOPE));
    assert!(out.flags.is_usable());
    // A Table 1 model on the same frame: unaffected.
    let mut t = Estimator::new(&b, &b);
    assert!(
        !t.step(&egi_frame(0, 5_000))
            .flags
            .has(Flags::OUT_OF_ENVELOPE)
    );
}

#[test]
fn table1_models_give_the_same_estimates_with_or_without_egi_channels() {
    let (a, b) = nets();
    let mut with = Estimator::new(&a, &b);
    let mut without = Estimator::new(&a, &b);
    for s in 0..40 {
        let f = egi_frame(s, 200_000);
        assert_eq!(
            with.step(&f),
            without.step(&f.restricted_to(estimator_core::Suite::Table1))
        );
    }
}

#[test]
fn turbulence_beyond_the_trained_envelope_is_flagged_while_the_filter_has_input() {
    use estimator_core::normalize::TURBULENCE_BANDS;
    // α reads the filter's turbulence index and airspeed; β reads Table 1 channels only.
    let mut a = net_of(
        Feature::FilterTurbulence,
        Feature::FilterAirspeed,
        400_000_000,
    );
    let b = net(Channel::Rudder, Channel::GyroP, 400_000);
    // 40 frames at `v_east_mms`; whether each was flagged.
    let run = |a: &CascadeNet<Part1, Part2, 2, 3>, v_east_mms: i32| {
        let mut e = Estimator::new(a, &b);
        (0..40)
            .map(|s| {
                // `egi_frame`'s heading is constant: keep it moving, as a real one does.
                let mut f = egi_frame(s, v_east_mms);
                f.raw[Channel::Heading.index()] += i32::from(s % 3);
                let out = e.step(&f);
                assert!(out.flags.is_usable(), "frame {s}: {:?}", out.flags);
                out.flags.has(Flags::TURBULENCE)
            })
            .collect::<Vec<_>>()
    };
    // The default: no limit.
    assert!(run(&a, 200_000).iter().all(|t| !t));
    // A limit below any index: every frame with fresh filter output is flagged (this made-up
    // flight does not fit the force model, so the filter gates its updates and the index stays 0;
    // `filter::tests` covers the index itself).
    a.turbulence = TurbulenceEnvelope {
        speed_lo_mms: 60_000,
        band_mms: 20_000,
        limit_urad: [-1; TURBULENCE_BANDS],
    };
    assert!(run(&a, 200_000).iter().all(|t| *t));
    // Limits no index reaches: never.
    a.turbulence.limit_urad = [i32::MAX; TURBULENCE_BANDS];
    assert!(run(&a, 200_000).iter().all(|t| !t));
    // At walking speed the filter restarts on every frame (air speed below 1 m/s): its held
    // outputs are not judged, though the model's channels are all usable.
    a.turbulence.limit_urad = [-1; TURBULENCE_BANDS];
    assert!(run(&a, 0).iter().all(|t| !t));
    // Without filter input (the same frames as a Table 1 sender delivers them) α is held and
    // nothing is judged; β, which does not read the filter, is never flagged.
    let mut e = Estimator::new(&a, &b);
    let out = e.step(&egi_frame(0, 200_000).restricted_to(estimator_core::Suite::Table1));
    assert!(out.flags.has(Flags::ALPHA_HELD));
    assert!(!out.flags.has(Flags::TURBULENCE));
    let mut t1 = Estimator::new(&b, &b);
    assert!(!t1.step(&egi_frame(0, 200_000)).flags.has(Flags::TURBULENCE));
}

#[test]
fn filter_diverged_and_the_other_cautions_raise_their_own_sigma_terms() {
    use estimator_core::uncertainty::Term;
    let b = net(Channel::Rudder, Channel::GyroP, 400_000);
    // α reads the filter, which gates this made-up flight's updates (`FILTER_DIVERGED`), or not;
    // either α reads the 200 ms change of the elevator (`HISTORY_SHORT` on frames 0-3 and on
    // frame 14, after the lost frame 10).
    let with_filter = net_of(
        Feature::FilterAirspeed,
        Feature::Delta(Channel::Elevator, Lag::F4),
        400_000_000,
    );
    let without = net_of(
        Feature::Sensor(Channel::GpsSpeed),
        Feature::Delta(Channel::Elevator, Lag::F4),
        400_000_000,
    );
    let (mut diverged, mut caution_alone) = (0, 0);
    for a in [&with_filter, &without] {
        let mut e = Estimator::new(a, &b);
        for s in (0..40).filter(|&s| s != 10) {
            let mut f = egi_frame(s, 200_000);
            f.raw[Channel::Heading.index()] += i32::from(s % 3);
            let flags = e.step(&f).flags;
            let terms = e.sigma_terms();
            let on = |set: bool| if set { 1_000 } else { 0 };
            let fd = flags.has(Flags::FILTER_DIVERGED);
            let caution = flags.0 & Flags::CAUTIONS != 0;
            for (angle, held) in [(0, Flags::ALPHA_HELD), (1, Flags::BETA_HELD)] {
                if flags.has(held) {
                    continue;
                }
                let t = terms[angle];
                assert_eq!(
                    t[Term::FilterDiverged as usize],
                    on(fd),
                    "frame {s}: {flags:?}"
                );
                assert_eq!(
                    t[Term::Caution as usize],
                    on(caution),
                    "frame {s}: {flags:?}"
                );
            }
            diverged += usize::from(fd);
            caution_alone += usize::from(caution && !fd);
        }
    }
    // Both cases occur, so the assertions above are about something.
    assert!(
        diverged > 0 && caution_alone > 0,
        "{diverged} {caution_alone}"
    );
    assert_eq!(Flags::CAUTIONS & Flags::FILTER_DIVERGED, 0);
}

#[test]
fn a_filter_lift_scale_outside_training_flags_a_model_that_does_not_read_it() {
    // α reads the filter's α and β, not its lift scale; β reads Table 1 channels only.
    let mut a = net_of(Feature::FilterAlpha, Feature::FilterBeta, 400_000_000);
    let b = net(Channel::Rudder, Channel::GyroP, 400_000);
    let flagged = |a: &CascadeNet<Part1, Part2, 2, 3>| {
        let mut e = Estimator::new(a, &b);
        (0..40)
            .map(|s| {
                let mut f = egi_frame(s, 200_000);
                f.raw[Channel::Heading.index()] += i32::from(s % 3);
                e.step(&f).flags.has(Flags::OUT_OF_ENVELOPE)
            })
            .collect::<Vec<_>>()
    };
    // No recorded range: never.
    assert!(flagged(&a).iter().all(|f| !f));
    // A range that holds the filter's lift scale (it starts at 1 and this made-up flight moves it
    // little): never.
    a.lift_scale = Envelope {
        lo: 5_000,
        hi: 15_000,
    };
    assert!(flagged(&a).iter().all(|f| !f));
    // A range the lift scale is outside of: every frame.
    a.lift_scale = Envelope {
        lo: 20_000,
        hi: 30_000,
    };
    assert!(flagged(&a).iter().all(|f| *f));
    // The check is the range's, not the filter's: a model that does not run the filter reads a
    // lift scale of 0, so `trainer::pipeline::train_angle` exports `ANY` for it.
    let mut t = net(Channel::Rudder, Channel::GyroP, 400_000);
    t.lift_scale = Envelope {
        lo: 5_000,
        hi: 15_000,
    };
    let mut e = Estimator::new(&t, &b);
    assert!(
        e.step(&egi_frame(0, 200_000))
            .flags
            .has(Flags::OUT_OF_ENVELOPE)
    );
}

#[test]
fn every_flag_bit_has_one_distinct_name_in_bit_order() {
    let bits: Vec<u16> = Flags::NAMED.iter().map(|(b, _)| *b).collect();
    let expected: Vec<u16> = (0..Flags::NAMED.len()).map(|k| 1u16 << k).collect();
    assert_eq!(bits, expected);
    let mut names: Vec<&str> = Flags::NAMED.iter().map(|(_, n)| *n).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), Flags::NAMED.len());
    // Every bit of the field is named, the last one included: the field is full.
    assert_eq!(Flags::NAMED.len(), 16);
    assert_eq!(Flags::GYRO_DISAGREES, 1 << 15);
}
