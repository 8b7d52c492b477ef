//! The 1σ of each estimate: how far the angle is likely off, from what this step saw.
//!
//! An estimate's error grows with what the networks cannot see in training: turbulence beyond
//! the filter's, an airframe that is not the model (the filter's lift scale leaves 1, the network
//! and the filter part ways), a filter that is unsure or inconsistent, a clamped input. Each of
//! those is a [`Term`], an integer in millidegrees (≥ 0) computed from the step's features and
//! flags, and
//!
//! ```text
//! σ² = Σₖ (wₖ · tₖ / 256)²        (millidegrees², integer)
//! ```
//!
//! with one weight per term and angle ([`Coefficients`], Q8). The weights are not chosen by hand:
//! `trainer fit-sigma` fits them (Gaussian likelihood, then one common factor for 95 % of the
//! frames within 2σ) on flights no network trained on, of randomised airframes and of JSBSim's
//! own, and writes `src/model/NAME/sigma.rs` (docs/results/uncertainty.md). A held or missing angle
//! has no 1σ: [`SIGMA_UNKNOWN`].
//!
//! Integer arithmetic throughout: every term is clamped to [`TERM_MAX`], so each product fits 64
//! bits and their sum saturates; no input panics.

use crate::features::{Feature, FeatureValues, urad_to_mdeg as mdeg};

/// The 1σ of an angle that was not computed this step (held, or no estimate).
pub const SIGMA_UNKNOWN: u16 = u16::MAX;
/// The largest 1σ reported for a computed angle, millidegrees.
pub const SIGMA_MAX: u16 = u16::MAX - 1;
/// Every term is clamped to this, millidegrees (1000°).
pub const TERM_MAX: u32 = 1_000_000;
/// An indicator term's size when it is set: one degree.
const ONE_DEG: u32 = 1_000;
/// [`Feature::FilterNisMean`] of a consistent filter (the measurement's 2 degrees of freedom),
/// in its 1e-3 units.
const NIS_CONSISTENT: i64 = 2_000;
/// The ρV², Pa, at which [`Term::TurbulenceSlow`] equals the turbulence index (a dynamic pressure of
/// 10 kPa), and the least ρV² it divides by (20 times the index at most).
pub const RHO_V2_REF_PA: i64 = 20_000;
pub const RHO_V2_FLOOR_PA: i64 = 1_000;

/// What the 1σ of an angle is made of. Every term is in millidegrees.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(usize)]
pub enum Term {
    /// Always one degree: the error floor of the networks in calm air.
    Base,
    /// The air-data filter's own 1σ of this angle.
    FilterSigma,
    /// |this angle − the filter's|, when the filter is clear ([`FeatureValues::filter_clear`]).
    Disagreement,
    /// The disagreement's running mean over about 25 s ([`SlowMean`]): a network and a filter that
    /// part ways for long do so because the airframe is not the model they know, not by noise.
    SlowDisagreement,
    /// The filter's turbulence index.
    Turbulence,
    /// |lift scale − 1| · |filter α|: the α the lift model misses on an airframe unlike the model.
    LiftMismatch,
    /// |side-force scale − 1| · |filter β|: the β the side-force model misses.
    SideMismatch,
    /// |this angle|: a force derivative that is not the model's (5–15 % on a real airframe) errs
    /// in proportion to the angle it is read from.
    Magnitude,
    /// The filter's 2-s NIS mean above that of a consistent filter, in its 1e-3 units over 10.
    NisExcess,
    /// One degree when the filter is not clear (no filter, restarted, gated, unsure, slow).
    FilterUnclear,
    /// One degree with `OUT_OF_ENVELOPE` ([`Indicators::out_of_envelope`]).
    OutOfEnvelope,
    /// One degree with `TURBULENCE` ([`Indicators::turbulent`]).
    Turbulent,
    /// One degree with a caution of `Flags::CAUTIONS` (not `FILTER_DIVERGED`, which has its own
    /// term; [`Indicators::caution`]).
    Caution,
    /// One degree with `FILTER_DIVERGED` ([`Indicators::filter_diverged`]): a step on which the
    /// filter gave its prediction alone or kept failing its gate costs more than a frame lost on
    /// the link, so it has its own weight.
    FilterDiverged,
    /// The turbulence index times [`RHO_V2_REF_PA`] / ρV²: the index is the change of the
    /// filter's wind estimate, and the filter follows a gust through the force it makes, which
    /// falls with the dynamic pressure; in slow flight (stall approaches at 2-3 kPa) the index
    /// reads a small part of the gusts that the α network then misses (docs/filter.md).
    TurbulenceSlow,
}

/// How many terms there are.
pub const TERMS: usize = 15;

impl Term {
    /// Every term, in index order.
    pub const ALL: [Term; TERMS] = [
        Term::Base,
        Term::FilterSigma,
        Term::Disagreement,
        Term::SlowDisagreement,
        Term::Turbulence,
        Term::LiftMismatch,
        Term::SideMismatch,
        Term::Magnitude,
        Term::NisExcess,
        Term::FilterUnclear,
        Term::OutOfEnvelope,
        Term::Turbulent,
        Term::Caution,
        Term::FilterDiverged,
        Term::TurbulenceSlow,
    ];

    pub const fn name(self) -> &'static str {
        match self {
            Term::Base => "base",
            Term::FilterSigma => "filter_sigma",
            Term::Disagreement => "disagreement",
            Term::SlowDisagreement => "slow_disagreement",
            Term::Turbulence => "turbulence",
            Term::LiftMismatch => "lift_mismatch",
            Term::SideMismatch => "side_mismatch",
            Term::Magnitude => "magnitude",
            Term::NisExcess => "nis_excess",
            Term::FilterUnclear => "filter_unclear",
            Term::OutOfEnvelope => "out_of_envelope",
            Term::Turbulent => "turbulent",
            Term::Caution => "caution",
            Term::FilterDiverged => "filter_diverged",
            Term::TurbulenceSlow => "turbulence_slow",
        }
    }
}

/// What the estimate's flags say, as the indicator terms read it (the estimator fills it in from
/// its `Flags`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Indicators {
    /// `OUT_OF_ENVELOPE`.
    pub out_of_envelope: bool,
    /// `TURBULENCE`.
    pub turbulent: bool,
    /// `HISTORY_SHORT`, `GPS_SUBSTITUTED`, `ALPHA_FROM_FILTER` or `BETA_DISAGREES`.
    pub caution: bool,
    /// `FILTER_DIVERGED`.
    pub filter_diverged: bool,
}

/// Which angle a 1σ is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Angle {
    Alpha,
    Beta,
}

/// The weights of both angles' terms, Q8 (256 = 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Coefficients {
    pub alpha: [u16; TERMS],
    pub beta: [u16; TERMS],
}

/// The weights of a build whose aircraft has no 1σ fit yet: every term at the largest weight, so
/// that every computed angle's 1σ is [`SIGMA_MAX`] (its base term is never 0) and every estimate is
/// `UNCERTAIN`: nothing is known of its error until `trainer fit-sigma` has measured it.
pub const UNFITTED: Coefficients = Coefficients {
    alpha: [u16::MAX; TERMS],
    beta: [u16::MAX; TERMS],
};

impl Coefficients {
    pub const fn of(&self, angle: Angle) -> &[u16; TERMS] {
        match angle {
            Angle::Alpha => &self.alpha,
            Angle::Beta => &self.beta,
        }
    }
}

/// µrad to millidegrees, magnitude, clamped to [`TERM_MAX`].
fn urad_to_mdeg(urad: i32) -> u32 {
    clamp_term(mdeg(i64::from(urad)).saturating_abs())
}

fn clamp_term(v: i64) -> u32 {
    // In [0, TERM_MAX], so the conversion is exact.
    u32::try_from(v.clamp(0, i64::from(TERM_MAX))).unwrap_or(TERM_MAX)
}

/// Frames over which [`track`] averages, as a power of two: 2⁹ = 512 frames, 25.6 s at 20 Hz.
pub const SLOW_SHIFT: u32 = 9;

/// The running mean of the disagreement term over 2^[`SLOW_SHIFT`] frames, of the steps where the
/// filter was clear. It is kept scaled by 2^[`SLOW_SHIFT`] so that a small disagreement moves it
/// too (an unscaled integer mean would not move for a disagreement below 512 mdeg).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SlowMean {
    scaled: u32,
}

impl SlowMean {
    /// The mean, millidegrees.
    pub fn mdeg(self) -> u32 {
        self.scaled >> SLOW_SHIFT
    }

    /// Folds in this step's `terms` (held when the filter was not clear).
    pub fn track(&mut self, terms: &[u32; TERMS]) {
        let unclear = terms
            .get(Term::FilterUnclear as usize)
            .copied()
            .unwrap_or(0);
        let Some(&d) = terms.get(Term::Disagreement as usize) else {
            return;
        };
        if unclear == 0 {
            // d ≤ TERM_MAX = 10⁶, so the scaled mean stays below 10⁶ · 2⁹ < 2³²; the saturating
            // forms only say so to the overflow lint.
            let decay = self.scaled >> SLOW_SHIFT;
            self.scaled = self
                .scaled
                .saturating_sub(decay)
                .saturating_add(d.min(TERM_MAX));
        }
    }
}

/// The terms of `angle` whose computed value is `angle_mdeg`, from the step's features, what the
/// estimate's flags say and the disagreement's running mean `slow_mdeg` ([`SlowMean`], before
/// this step).
pub fn terms(
    angle: Angle,
    values: &FeatureValues,
    angle_mdeg: i32,
    flags: Indicators,
    slow_mdeg: u32,
) -> [u32; TERMS] {
    let (filter_angle, filter_sigma) = match angle {
        Angle::Alpha => (Feature::FilterAlpha, Feature::FilterSigmaAlpha),
        Angle::Beta => (Feature::FilterBeta, Feature::FilterSigmaBeta),
    };
    let clear = values.filter_clear();
    let filter_mdeg = mdeg(i64::from(values.get(filter_angle)));
    let disagreement = if clear {
        clamp_term(
            i64::from(angle_mdeg)
                .saturating_sub(filter_mdeg)
                .saturating_abs(),
        )
    } else {
        0
    };
    // The filter's outputs mean something once it has run (an airspeed).
    let ran = values.get(Feature::FilterAirspeed) > 0;
    // A force scale in 1e-4 times the filter's angle it scales: |scale − 1| · |angle|.
    let mismatch = |scale: Feature, angle: Feature| {
        if ran {
            clamp_term(
                i64::from(values.get(scale))
                    .saturating_sub(10_000)
                    .saturating_abs()
                    .saturating_mul(i64::from(urad_to_mdeg(values.get(angle))))
                    / 10_000,
            )
        } else {
            0
        }
    };
    let nis_excess = if ran {
        clamp_term(
            i64::from(values.get(Feature::FilterNisMean)).saturating_sub(NIS_CONSISTENT) / 10,
        )
    } else {
        0
    };
    // The turbulence index scaled by the reference ρV² over the frame's (at least the floor, so
    // never 0), so at most 20 times the index (≤ TERM_MAX × 20: fits i64).
    let turbulence_slow = if ran {
        let rho_v2 = i64::from(values.get(Feature::RhoV2)).max(RHO_V2_FLOOR_PA);
        clamp_term(
            i64::from(urad_to_mdeg(values.get(Feature::FilterTurbulence)))
                .saturating_mul(RHO_V2_REF_PA)
                .checked_div(rho_v2)
                .unwrap_or(i64::from(TERM_MAX)),
        )
    } else {
        0
    };
    let on = |set: bool| if set { ONE_DEG } else { 0 };
    let mut t = [0u32; TERMS];
    for (slot, term) in t.iter_mut().zip(Term::ALL) {
        *slot = match term {
            Term::Base => ONE_DEG,
            Term::FilterSigma => urad_to_mdeg(values.get(filter_sigma)),
            Term::Disagreement => disagreement,
            Term::SlowDisagreement => slow_mdeg.min(TERM_MAX),
            Term::Turbulence => urad_to_mdeg(values.get(Feature::FilterTurbulence)),
            Term::LiftMismatch => mismatch(Feature::FilterLiftScale, Feature::FilterAlpha),
            Term::SideMismatch => mismatch(Feature::FilterSideScale, Feature::FilterBeta),
            Term::Magnitude => clamp_term(i64::from(angle_mdeg).saturating_abs()),
            Term::NisExcess => nis_excess,
            Term::FilterUnclear => on(!clear),
            Term::OutOfEnvelope => on(flags.out_of_envelope),
            Term::Turbulent => on(flags.turbulent),
            Term::Caution => on(flags.caution),
            Term::FilterDiverged => on(flags.filter_diverged),
            Term::TurbulenceSlow => turbulence_slow,
        };
    }
    t
}

/// The 1σ, millidegrees, of `terms` weighted by `weights` (Q8): at most [`SIGMA_MAX`].
pub fn sigma(weights: &[u16; TERMS], terms: &[u32; TERMS]) -> u16 {
    let sum = weights.iter().zip(terms).fold(0u64, |acc, (&w, &t)| {
        // ≤ 65,535 · 1,000,000 / 256 < 2^28: its square is below 2^56, and the sum saturates
        // (the saturating forms only say so to the overflow lint).
        let p = u64::from(w).saturating_mul(u64::from(t.min(TERM_MAX))) >> 8;
        acc.saturating_add(p.saturating_mul(p))
    });
    u16::try_from(sum.isqrt()).map_or(SIGMA_MAX, |s| s.min(SIGMA_MAX))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Channel, History, SensorFrame};

    #[test]
    fn sigma_is_the_root_sum_of_squares_of_the_weighted_terms() {
        let mut w = [0u16; TERMS];
        let mut t = [0u32; TERMS];
        // 1.5 × 2000 and 0.5 × 8000 mdeg: √(3000² + 4000²) = 5000.
        (w[0], t[0]) = (384, 2_000);
        (w[3], t[3]) = (128, 8_000);
        assert_eq!(sigma(&w, &t), 5_000);
        assert_eq!(sigma(&[0; TERMS], &t), 0);
    }

    #[test]
    fn the_largest_weights_and_terms_saturate_below_unknown() {
        assert_eq!(sigma(&[u16::MAX; TERMS], &[u32::MAX; TERMS]), SIGMA_MAX);
        assert_ne!(SIGMA_MAX, SIGMA_UNKNOWN);
    }

    #[test]
    fn without_a_filter_only_the_base_and_the_filter_unclear_term_are_set() {
        let v = FeatureValues::compute(&SensorFrame::default(), &History::new());
        for angle in [Angle::Alpha, Angle::Beta] {
            let t = terms(angle, &v, 1_234, Indicators::default(), 0);
            let mut want = [0u32; TERMS];
            want[Term::Base as usize] = ONE_DEG;
            want[Term::FilterUnclear as usize] = ONE_DEG;
            want[Term::Magnitude as usize] = 1_234;
            assert_eq!(t, want);
        }
        let t = terms(
            Angle::Beta,
            &v,
            0,
            Indicators {
                out_of_envelope: true,
                caution: true,
                ..Indicators::default()
            },
            7,
        );
        assert_eq!(t[Term::SlowDisagreement as usize], 7);
        assert_eq!(t[Term::OutOfEnvelope as usize], ONE_DEG);
        assert_eq!(t[Term::Caution as usize], ONE_DEG);
        assert_eq!(t[Term::Turbulent as usize], 0);
        assert_eq!(t[Term::FilterDiverged as usize], 0);
        let diverged = Indicators {
            filter_diverged: true,
            ..Indicators::default()
        };
        let t = terms(Angle::Alpha, &v, 0, diverged, 0);
        assert_eq!(t[Term::FilterDiverged as usize], ONE_DEG);
        assert_eq!(t[Term::Caution as usize], 0);
    }

    #[test]
    fn a_clear_filter_gives_the_disagreement_and_the_force_mismatches() {
        let mut v = FeatureValues::compute(&SensorFrame::default(), &History::new());
        v.set_filter(&crate::filter::Output {
            alpha_rad: 0.1,
            beta_rad: -0.02,
            sigma_alpha_rad: 0.004,
            airspeed_mps: 150.0,
            lift_scale: 1.1,
            side_scale: 0.85,
            nis_mean: 2.5,
            turbulence_rad: 0.01,
            ..Default::default()
        });
        assert!(v.filter_clear());
        // Filter α 0.1 rad = 5729 mdeg; the network says 6229.
        let t = terms(Angle::Alpha, &v, 6_229, Indicators::default(), 0);
        assert_eq!(t[Term::Disagreement as usize], 500);
        assert_eq!(t[Term::FilterSigma as usize], 229);
        // |1.1 − 1| × 5729 mdeg.
        assert_eq!(t[Term::LiftMismatch as usize], 572);
        // |0.85 − 1| × 1145 mdeg (filter β −0.02 rad), for either angle.
        assert_eq!(t[Term::SideMismatch as usize], 171);
        assert_eq!(t[Term::NisExcess as usize], 50);
        assert_eq!(t[Term::FilterUnclear as usize], 0);
        assert_eq!(t[Term::Magnitude as usize], 6_229);
        // Turbulence 0.01 rad = 572 mdeg; with no GPS speed ρV² is below its 1,000-Pa floor, so
        // the slow-flight term is 20 times the index, for either angle.
        assert_eq!(t[Term::Turbulence as usize], 572);
        assert!(v.get(Feature::RhoV2) < 1_000);
        assert_eq!(t[Term::TurbulenceSlow as usize], 11_440);
        assert_eq!(
            terms(Angle::Beta, &v, 0, Indicators::default(), 0)[Term::TurbulenceSlow as usize],
            11_440
        );
        // At 100 m/s at sea level ρV² is 12,250 Pa (ISA 1.225 kg/m³): 572 × 20,000 / ρV².
        let mut frame = SensorFrame::default();
        frame.set_everywhere(Channel::GpsSpeed, 100_000);
        frame.set_everywhere(Channel::GpsAlt, 0);
        let mut fast = FeatureValues::compute(&frame, &History::new());
        fast.set_filter(&crate::filter::Output {
            airspeed_mps: 100.0,
            turbulence_rad: 0.01,
            ..Default::default()
        });
        let rho_v2 = fast.get(Feature::RhoV2);
        assert!((12_240..=12_260).contains(&rho_v2), "ρV² {rho_v2} Pa");
        let slow = terms(Angle::Alpha, &fast, 0, Indicators::default(), 0);
        assert_eq!(
            slow[Term::TurbulenceSlow as usize],
            11_440_000 / rho_v2 as u32
        );
        assert!((930..=936).contains(&slow[Term::TurbulenceSlow as usize]));
        // The running mean moves 1/512 of the way per clear step, even for a small disagreement,
        // reaches it, and holds while the filter is not clear.
        let mut slow = SlowMean::default();
        slow.track(&t);
        assert_eq!(slow, SlowMean { scaled: 500 });
        for _ in 0..20 * 512 {
            slow.track(&t);
        }
        assert_eq!(slow.mdeg(), 500);
        let mut unclear = t;
        unclear[Term::FilterUnclear as usize] = ONE_DEG;
        let before = slow;
        slow.track(&unclear);
        assert_eq!(slow, before);
    }
}
