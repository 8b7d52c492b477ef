//! The aircraft's aerodynamic force model, as JSBSim flies it: lift, drag and side-force
//! coefficients and their body-axis components, with their slopes in α and β for a model-based
//! filter.
//!
//! The model itself is data in [`tables`] ([`MODEL`]), generated from the JSBSim model the
//! aircraft description names (the F-16's: the `jsbsim` package's `aircraft/f16/f16.xml`, or, with
//! `ESTIMATOR_AERO`, another aircraft directory's) by `scripts/extract-aero` and never edited by
//! hand. This module only knows
//! how JSBSim evaluates such data:
//! * every term of an axis is a product of factors ([`Factor`]): constants, state and surface
//!   values ([`Var`]) and table lookups ([`Table1`], [`Table2`]); JSBSim's `qbar·Sw` is divided out;
//! * a table is JSBSim's `FGTable`: linear in each dimension between the breakpoints, the end
//!   value beyond them (no extrapolation); on a 2-D table the row is blended first;
//! * the DRAG, SIDE and LIFT sums are wind-axis forces, turned into body axes with JSBSim's
//!   `Tw2b(α, β)` applied to `(−drag, side, −lift)`.
//!
//! f32 throughout, no heap, no panics. Inputs that are not finite (or a true airspeed that is not
//! positive) give all-zero coefficients with `valid == false`; NaN or ±Inf never comes out.
//! `hil-sim/tests/aero_model_parity.rs` checks the result against JSBSim's own terms and forces.

/// The tables: `NAME_tables.rs` beside this file for the build's aircraft (`ESTIMATOR_AIRCRAFT`,
/// default `f16`), or the file `ESTIMATOR_AERO` names at build time (`build.rs`;
/// `scripts/calibrate` builds a calibrated aircraft's tables this way).
#[rustfmt::skip]
// The numbers are the XML's own (an engine deck's 1.1284 is not 2/√π).
#[allow(clippy::approx_constant)]
pub mod tables {
    include!(env!("ESTIMATOR_AERO_FILE"));
}

pub use tables::{ENGINE, MODEL, MOMENTS};

mod engine;
pub use engine::{
    Engine, EngineLookup, EngineTable, Propeller, PropellerLookup, PropellerTable, Turbine,
};

/// Travel of one flaperon at norm ±1, in degrees: the convention of the `Flaperon` channel, from
/// the aircraft description (its sensor's `deg_per_unit`). JSBSim's model has no degree property
/// for it. 1 on an airframe without flaperons (their channel carries 0, the mix is 0).
pub const FLAPERON_DEG_PER_NORM: f32 =
    match crate::aircraft::AIRCRAFT.surface(crate::Channel::Flaperon) {
        Some(s) => s.deg_per_unit as f32,
        None => 1.0,
    };

const FT_TO_M: f32 = 0.3048;

/// A quantity a term or a table key reads, in JSBSim's units (its property in the docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Var {
    /// `aero/alpha-rad`.
    AlphaRad,
    /// `aero/beta-rad`.
    BetaRad,
    /// `velocities/mach`.
    Mach,
    /// `fcs/elevator-pos-rad`.
    ElevatorRad,
    /// `fcs/aileron-pos-rad`.
    AileronRad,
    /// `fcs/rudder-pos-rad`.
    RudderRad,
    /// `fcs/lef-pos-rad`.
    LefRad,
    /// `fcs/speedbrake-pos-rad`.
    SpeedbrakeRad,
    /// `fcs/flaperon-mix-rad`.
    FlaperonMixRad,
    /// `gear/gear-pos-norm`.
    GearNorm,
    /// `velocities/p-aero-rad_sec`.
    PAeroRps,
    /// `velocities/q-aero-rad_sec`.
    QAeroRps,
    /// `velocities/r-aero-rad_sec`.
    RAeroRps,
    /// `aero/bi2vel`: wingspan / (2 · true airspeed), s.
    Bi2Vel,
    /// `aero/ci2vel`: chord / (2 · true airspeed), s.
    Ci2Vel,
    /// `aero/h_b-mac-ft`: height of the aero reference point above ground / wingspan.
    HOverBMac,
    /// `aero/mag-beta-rad`: |β| (its slope in β is β's sign).
    MagBetaRad,
    /// `fcs/mag-elevator-pos-rad`: |elevator|.
    MagElevatorRad,
    /// `fcs/left-aileron-pos-rad`: the left aileron (models with one aileron property per side).
    LeftAileronRad,
    /// `aero/alphadot-rad_sec`: α̇.
    AlphaDotRps,
    /// `fcs/flap-pos-deg`: trailing-edge flap, degrees.
    FlapDeg,
    /// `aero/stall-hyst-norm`: JSBSim's stall-hysteresis latch (1 once α passes the model's upper
    /// hysteresis limit, 0 again below its lower one).
    StallHystNorm,
    /// The dynamic pressure in the propeller's slipstream over q̄: a moment term whose product
    /// carries the model's slipstream dynamic pressure, ½·ρ·(u + k·v_induced)² (the c172p's
    /// `aero/function/qbar-induced-psf`), in place of q̄ (`scripts/extract-aero` checks the
    /// function's form; k is [`Moments::slipstream_induced_factor`]). No force term reads it:
    /// [`Point::new`] sets 1, and flight-test calibration, which knows the propeller's speed, sets
    /// it ([`Moments::slipstream_qbar_ratio`]).
    SlipstreamQbarRatio,
}

/// A value with its partial derivatives in α and β (per radian).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Partial {
    pub value: f32,
    pub d_alpha: f32,
    pub d_beta: f32,
}

impl Partial {
    const ONE: Partial = Partial {
        value: 1.0,
        d_alpha: 0.0,
        d_beta: 0.0,
    };

    fn times(self, o: Partial) -> Partial {
        Partial {
            value: self.value * o.value,
            d_alpha: self.d_alpha * o.value + self.value * o.d_alpha,
            d_beta: self.d_beta * o.value + self.value * o.d_beta,
        }
    }

    fn plus(self, o: Partial) -> Partial {
        Partial {
            value: self.value + o.value,
            d_alpha: self.d_alpha + o.d_alpha,
            d_beta: self.d_beta + o.d_beta,
        }
    }

    /// A value that depends on `v` alone, with slope `slope` in it, at `p`: its partials are the
    /// slope times `v`'s own in α and β. α's and β's are 1; |β|'s in β is β's sign (+1 at β = 0, a
    /// convention: JSBSim computes no slopes); every other variable's are 0. Comparisons rather
    /// than a `match`: this runs for every factor and key, and the chain is the cheaper on the M4.
    fn through(p: &Point, v: Var, value: f32, slope: f32) -> Partial {
        Partial {
            value,
            d_alpha: if v == Var::AlphaRad { slope } else { 0.0 },
            d_beta: if v == Var::BetaRad {
                slope
            } else if v == Var::MagBetaRad {
                if p.beta_rad < 0.0 { -slope } else { slope }
            } else {
                0.0
            },
        }
    }
}

/// Everything the model reads, in JSBSim's units: one operating point.
///
/// [`Point::new`] makes it from the estimator's quantities; a caller holding JSBSim's own property
/// values (a test) may fill it directly, |β| and |δe| included. One field per [`Var`], in `Var`'s
/// order, so that [`Point::get`] is one load at an offset (it runs for every factor and table key
/// of every model evaluation, four per filter step): computed arms there cost the flight image
/// about 5,000 instructions per step.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[repr(C)]
pub struct Point {
    pub alpha_rad: f32,
    pub beta_rad: f32,
    pub mach: f32,
    pub elevator_rad: f32,
    pub aileron_rad: f32,
    pub rudder_rad: f32,
    pub lef_rad: f32,
    pub speedbrake_rad: f32,
    pub flaperon_mix_rad: f32,
    pub gear_norm: f32,
    pub p_aero_rps: f32,
    pub q_aero_rps: f32,
    pub r_aero_rps: f32,
    pub bi2vel_s: f32,
    pub ci2vel_s: f32,
    pub h_over_b: f32,
    /// |β| and |δe|.
    pub mag_beta_rad: f32,
    pub mag_elevator_rad: f32,
    pub left_aileron_rad: f32,
    pub alpha_dot_rps: f32,
    pub flap_deg: f32,
    pub stall_hyst_norm: f32,
    pub slipstream_qbar_ratio: f32,
}

/// The air-relative state.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct AirState {
    /// Angle of attack, rad.
    pub alpha_rad: f32,
    /// Sideslip, rad.
    pub beta_rad: f32,
    pub mach: f32,
    /// True airspeed, m/s: scales the rates (JSBSim's `b/(2V)`, `c/(2V)`).
    pub tas_mps: f32,
    /// Body rates relative to the air mass, rad/s. JSBSim's aero uses `velocities/*-aero-rad_sec`
    /// (the inertial rates minus the rotational turbulence), not what a gyro measures.
    pub p_rps: f32,
    pub q_rps: f32,
    pub r_rps: f32,
    /// Height of the aerodynamic reference point above ground over the wingspan (JSBSim's
    /// `aero/h_b-mac-ft`, a ratio despite its name). Ground effect on lift ends at 1.1: any larger
    /// value (e.g. [`AirState::NO_GROUND_EFFECT`]) is out of ground effect.
    pub h_over_b: f32,
    /// What the model reads beyond the air-data point: α̇ and the stall latch.
    pub unsteady: Unsteady,
}

/// What a force model reads beyond the air-data point, for models with such terms (JSBSim's
/// `aero/alphadot-rad_sec` and `aero/stall-hyst-norm`; a model without them ignores both).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Unsteady {
    /// Rate of change of α, rad/s.
    pub alpha_dot_rps: f32,
    /// JSBSim's stall-hysteresis latch (`aero/stall-hyst-norm` = 1): set once α rose above the
    /// model's upper hysteresis limit, until it falls below the lower one ([`Model::stall_latch`]).
    pub stall_latched: bool,
}

impl AirState {
    /// A [`AirState::h_over_b`] far above any ground effect.
    pub const NO_GROUND_EFFECT: f32 = 1000.0;
}

/// Control-surface positions in the sensor channels' units (degrees, see [`crate::channels`]).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Surfaces {
    /// Elevator (`fcs/elevator-pos-deg`).
    pub elevator_deg: f32,
    /// Aileron (`fcs/aileron-pos-rad` in degrees).
    pub aileron_deg: f32,
    /// Rudder (`fcs/rudder-pos-deg`).
    pub rudder_deg: f32,
    /// Leading-edge flap as the aero model sees it: JSBSim's aero reads the scheduled
    /// `fcs/lef-pos-rad`, not the rate-limited actuator `fcs/lef-pos-deg` the `Lef` channel carries.
    pub lef_deg: f32,
    /// Left and right flaperon, degrees at [`FLAPERON_DEG_PER_NORM`] per norm. The aero reads only
    /// their sum (`fcs/flaperon-mix-rad`); the `Flaperon` channel carries the left one alone.
    pub flaperon_left_deg: f32,
    pub flaperon_right_deg: f32,
    /// Speedbrake (`fcs/speedbrake-pos-deg`).
    pub speedbrake_deg: f32,
    /// Trailing-edge flap, degrees (the `Tef` channel): what a model with `fcs/flap-pos-deg`
    /// reads (a light aircraft's flap; the F-16's model reads its flaps through the flaperons).
    pub flap_deg: f32,
    /// Landing gear, 0 up … 1 down (`gear/gear-pos-norm`).
    pub gear_norm: f32,
}

impl Point {
    /// The operating point for `model`; `None` if an input is not finite or the airspeed is not
    /// positive.
    pub fn new(model: &Model<'_>, air: &AirState, s: &Surfaces) -> Option<Point> {
        let finite = [
            air.alpha_rad,
            air.beta_rad,
            air.mach,
            air.tas_mps,
            air.p_rps,
            air.q_rps,
            air.r_rps,
            air.h_over_b,
            air.unsteady.alpha_dot_rps,
            s.elevator_deg,
            s.aileron_deg,
            s.rudder_deg,
            s.lef_deg,
            s.flaperon_left_deg,
            s.flaperon_right_deg,
            s.speedbrake_deg,
            s.flap_deg,
            s.gear_norm,
        ]
        .iter()
        .all(|v| v.is_finite());
        if !finite || air.tas_mps <= 0.0 {
            return None;
        }
        let two_v = 2.0 * air.tas_mps;
        let elevator_rad = s.elevator_deg.to_radians();
        let p = Point {
            alpha_rad: air.alpha_rad,
            beta_rad: air.beta_rad,
            mach: air.mach,
            elevator_rad,
            aileron_rad: s.aileron_deg.to_radians(),
            rudder_rad: s.rudder_deg.to_radians(),
            lef_rad: s.lef_deg.to_radians(),
            speedbrake_rad: s.speedbrake_deg.to_radians(),
            flaperon_mix_rad: model.flaperon_mix_gain
                * (s.flaperon_left_deg + s.flaperon_right_deg)
                / FLAPERON_DEG_PER_NORM,
            gear_norm: s.gear_norm,
            p_aero_rps: air.p_rps,
            q_aero_rps: air.q_rps,
            r_aero_rps: air.r_rps,
            bi2vel_s: model.wingspan_ft * FT_TO_M / two_v,
            ci2vel_s: model.chord_ft * FT_TO_M / two_v,
            h_over_b: air.h_over_b,
            mag_beta_rad: libm::fabsf(air.beta_rad),
            mag_elevator_rad: libm::fabsf(elevator_rad),
            // The left aileron is the one aileron channel.
            left_aileron_rad: s.aileron_deg.to_radians(),
            alpha_dot_rps: air.unsteady.alpha_dot_rps,
            flap_deg: s.flap_deg,
            stall_hyst_norm: if air.unsteady.stall_latched { 1.0 } else { 0.0 },
            slipstream_qbar_ratio: 1.0,
        };
        // The inputs are finite (above), and so are their conversions; only the quotients by the
        // airspeed and the flaperon mix can still overflow.
        [p.bi2vel_s, p.ci2vel_s, p.flaperon_mix_rad]
            .iter()
            .all(|v| v.is_finite())
            .then_some(p)
    }

    pub fn get(&self, v: Var) -> f32 {
        match v {
            Var::AlphaRad => self.alpha_rad,
            Var::BetaRad => self.beta_rad,
            Var::Mach => self.mach,
            Var::ElevatorRad => self.elevator_rad,
            Var::AileronRad => self.aileron_rad,
            Var::RudderRad => self.rudder_rad,
            Var::LefRad => self.lef_rad,
            Var::SpeedbrakeRad => self.speedbrake_rad,
            Var::FlaperonMixRad => self.flaperon_mix_rad,
            Var::GearNorm => self.gear_norm,
            Var::PAeroRps => self.p_aero_rps,
            Var::QAeroRps => self.q_aero_rps,
            Var::RAeroRps => self.r_aero_rps,
            Var::Bi2Vel => self.bi2vel_s,
            Var::Ci2Vel => self.ci2vel_s,
            Var::HOverBMac => self.h_over_b,
            Var::MagBetaRad => self.mag_beta_rad,
            Var::MagElevatorRad => self.mag_elevator_rad,
            Var::LeftAileronRad => self.left_aileron_rad,
            Var::AlphaDotRps => self.alpha_dot_rps,
            Var::FlapDeg => self.flap_deg,
            Var::StallHystNorm => self.stall_hyst_norm,
            Var::SlipstreamQbarRatio => self.slipstream_qbar_ratio,
        }
    }

    fn is_finite(&self) -> bool {
        [
            self.alpha_rad,
            self.beta_rad,
            self.mach,
            self.elevator_rad,
            self.aileron_rad,
            self.rudder_rad,
            self.lef_rad,
            self.speedbrake_rad,
            self.flaperon_mix_rad,
            self.gear_norm,
            self.p_aero_rps,
            self.q_aero_rps,
            self.r_aero_rps,
            self.bi2vel_s,
            self.ci2vel_s,
            self.h_over_b,
            self.mag_beta_rad,
            self.mag_elevator_rad,
            self.left_aileron_rad,
            self.alpha_dot_rps,
            self.flap_deg,
            self.stall_hyst_norm,
            self.slipstream_qbar_ratio,
        ]
        .iter()
        .all(|v| v.is_finite())
    }
}

/// A table lookup at an operating point, with its slopes in α and β. Only this module can call it
/// (the lookup of a non-finite point is not checked); use [`Term::eval`] or [`Model`].
pub trait Lookup: Sync {
    #[doc(hidden)]
    fn look_up(&self, p: &Point, _: sealed::Token) -> Partial;
    /// Whether the table is looked up by `v` (one of its keys).
    fn reads(&self, v: Var) -> bool;
}

mod sealed {
    /// Makes [`super::Lookup::look_up`] uncallable outside this module.
    #[derive(Clone, Copy)]
    pub struct Token;
}

/// A 1-D table: `y(key)` at breakpoints `x`.
#[derive(Clone, Debug, PartialEq)]
pub struct Table1<const N: usize> {
    pub key: Var,
    pub x: [f32; N],
    pub y: [f32; N],
}

/// A 2-D table: `data[row][col]` at breakpoints `rows` × `cols`.
#[derive(Clone, Debug, PartialEq)]
pub struct Table2<const R: usize, const C: usize> {
    pub row: Var,
    pub col: Var,
    pub rows: [f32; R],
    pub cols: [f32; C],
    pub data: [[f32; C]; R],
}

/// Where `k` falls in breakpoints `bp`, as JSBSim's `FGTable` searches: the first segment whose
/// upper breakpoint is `>= k`, else the last one. Returns (index of the segment's lower breakpoint,
/// fraction clamped to [0, 1] as JSBSim clamps it, d fraction / d k: `1/span` strictly between the
/// end breakpoints, 0 at and beyond them).
fn segment(bp: &[f32], k: f32) -> Option<(usize, f32, f32)> {
    let mut found = None;
    for (i, (&lo, &hi)) in bp.iter().zip(bp.iter().skip(1)).enumerate() {
        // Spans are > 0: the generated file asserts strictly ascending breakpoints.
        let span = hi - lo;
        // JSBSim's Constrain(0, f, 1). (`clamp`'s bounds assertion folds away: constant bounds.)
        let f = ((k - lo) / span).clamp(0.0, 1.0);
        found = Some((i, f, 1.0 / span));
        if hi >= k {
            break;
        }
    }
    let (i, f, inv) = found?;
    let inside = matches!((bp.first(), bp.last()), (Some(&a), Some(&b)) if k > a && k < b);
    Some((i, f, if inside { inv } else { 0.0 }))
}

impl<const N: usize> Lookup for Table1<N> {
    fn reads(&self, v: Var) -> bool {
        self.key == v
    }

    fn look_up(&self, p: &Point, _: sealed::Token) -> Partial {
        let k = p.get(self.key);
        let ends = (self.x.first(), self.y.first(), self.x.last(), self.y.last());
        let (Some(&x0), Some(&y0), Some(&xn), Some(&yn)) = ends else {
            return Partial::default();
        };
        // JSBSim returns the end values themselves at and beyond the ends.
        if k <= x0 {
            return Partial::through(p, self.key, y0, 0.0);
        }
        if k >= xn {
            return Partial::through(p, self.key, yn, 0.0);
        }
        let Some((i, f, inv)) = segment(&self.x, k) else {
            return Partial::default();
        };
        let (Some(&ya), Some(&yb)) = (self.y.get(i), self.y.get(i.wrapping_add(1))) else {
            return Partial::default();
        };
        // JSBSim: Factor·(y1 − y0) + y0.
        Partial::through(p, self.key, f * (yb - ya) + ya, (yb - ya) * inv)
    }
}

impl<const R: usize, const C: usize> Lookup for Table2<R, C> {
    fn reads(&self, v: Var) -> bool {
        self.row == v || self.col == v
    }

    fn look_up(&self, p: &Point, _: sealed::Token) -> Partial {
        let (rk, ck) = (p.get(self.row), p.get(self.col));
        let (Some((r, rf, rinv)), Some((c, cf, cinv))) =
            (segment(&self.rows, rk), segment(&self.cols, ck))
        else {
            return Partial::default();
        };
        let cell = |ri: usize, ci: usize| {
            self.data
                .get(ri)
                .and_then(|row| row.get(ci))
                .copied()
                .unwrap_or(0.0)
        };
        let (r1, c1) = (r.wrapping_add(1), c.wrapping_add(1));
        let (a0, a1, b0, b1) = (cell(r, c), cell(r1, c), cell(r, c1), cell(r1, c1));
        // JSBSim blends along the row key first (rF·upper + (1 − rF)·lower in both columns), then
        // along the column key (cF·(col2 − col1) + col1); both fractions clamped, so the ends hold.
        let col1 = rf * a1 + (1.0 - rf) * a0;
        let col2 = rf * b1 + (1.0 - rf) * b0;
        let value = cf * (col2 - col1) + col1;
        let d_row = (cf * (b1 - b0) + (1.0 - cf) * (a1 - a0)) * rinv;
        let d_col = (col2 - col1) * cinv;
        Partial::through(p, self.row, value, d_row).plus(Partial::through(p, self.col, 0.0, d_col))
    }
}

/// One factor of a term's product.
#[derive(Clone, Copy)]
pub enum Factor<'a> {
    Const(f32),
    Var(Var),
    Table(&'a dyn Lookup),
}

impl Factor<'_> {
    /// Whether the factor reads `v`: is it, or a table looked up by it.
    pub fn reads(&self, v: Var) -> bool {
        match *self {
            Factor::Const(_) => false,
            Factor::Var(w) => w == v,
            Factor::Table(t) => t.reads(v),
        }
    }

    fn eval(&self, p: &Point) -> Partial {
        match *self {
            Factor::Const(c) => Partial {
                value: c,
                d_alpha: 0.0,
                d_beta: 0.0,
            },
            Factor::Var(v) => Partial::through(p, v, p.get(v), 1.0),
            Factor::Table(t) => t.look_up(p, sealed::Token),
        }
    }
}

/// One JSBSim aero function of a force axis, as a coefficient (its product over `qbar·Sw`).
#[derive(Clone, Copy)]
pub struct Term<'a> {
    /// The JSBSim function (and property) name, e.g. `aero/coefficient/CLDh`.
    pub name: &'static str,
    pub factors: &'a [Factor<'a>],
}

impl Term<'_> {
    /// The term's coefficient and slopes at `p`; `None` if `p` or the result is not finite.
    pub fn eval(&self, p: &Point) -> Option<Partial> {
        let v = self.partial(p);
        (p.is_finite() && [v.value, v.d_alpha, v.d_beta].iter().all(|x| x.is_finite())).then_some(v)
    }

    fn partial(&self, p: &Point) -> Partial {
        self.factors
            .iter()
            .fold(Partial::ONE, |acc, f| acc.times(f.eval(p)))
    }
}

/// An aircraft's moment axes (JSBSim's `ROLL`, `PITCH` and `YAW`, body axes, about the
/// aerodynamic reference point), each a sum of terms: roll and yaw over `qbar·Sw·bw`, pitch over
/// `qbar·Sw·cbarw`. Flight-test calibration identifies them; the flight software reads none.
#[derive(Clone, Copy)]
pub struct Moments<'a> {
    pub roll: &'a [Term<'a>],
    pub pitch: &'a [Term<'a>],
    pub yaw: &'a [Term<'a>],
    /// k of the slipstream's ½·ρ·(u + k·v_induced)² that [`Var::SlipstreamQbarRatio`] stands for
    /// (0: no term reads it).
    pub slipstream_induced_factor: f32,
}

impl Moments<'_> {
    /// [`Var::SlipstreamQbarRatio`] at true airspeed `tas_fps`, airspeed along body x `u_fps` and
    /// the propeller-induced velocity `induced_fps` (JSBSim's `prop-induced-velocity_fps`,
    /// [`super::Propeller::induced_fps`]): (u + k·v_induced)² / V². `None` if an input is not
    /// finite or the airspeed is not positive.
    pub fn slipstream_qbar_ratio(&self, tas_fps: f32, u_fps: f32, induced_fps: f32) -> Option<f32> {
        let v = u_fps + self.slipstream_induced_factor * induced_fps;
        let r = v * v / (tas_fps * tas_fps);
        (tas_fps > 0.0 && r.is_finite()).then_some(r)
    }

    /// The roll, pitch and yaw moment coefficients at `p`; `None` if `p` or a sum is not finite.
    pub fn coefficients_at(&self, p: &Point) -> Option<[f32; 3]> {
        let c = [self.roll, self.pitch, self.yaw].map(|terms| Model::axis(terms, p).value);
        (p.is_finite() && c.iter().all(|v| v.is_finite())).then_some(c)
    }
}

/// An aircraft's force model: three wind-axis sums and the constants its inputs need.
#[derive(Clone, Copy)]
pub struct Model<'a> {
    pub drag: &'a [Term<'a>],
    pub side: &'a [Term<'a>],
    pub lift: &'a [Term<'a>],
    /// `metrics/Sw-sqft`: what the coefficients multiply with dynamic pressure.
    pub wing_area_ft2: f32,
    pub wingspan_ft: f32,
    pub chord_ft: f32,
    /// `fcs/flaperon-mix-rad` per unit of (left + right flaperon norm).
    pub flaperon_mix_gain: f32,
    /// JSBSim's stall latch `aero/stall-hyst-norm` (its `<hysteresis_limits>`): cleared below the
    /// first α (rad), set above the second; `None` when no term reads it.
    pub stall_hysteresis_rad: Option<(f32, f32)>,
}

impl Model<'_> {
    /// The stall latch after a step at `alpha_rad`, as JSBSim's `FGAerodynamics` moves it: set
    /// above the upper hysteresis limit, cleared below the lower one, held between them; always
    /// clear for a model without limits. A non-finite α holds it.
    pub fn stall_latch(&self, latched: bool, alpha_rad: f32) -> bool {
        match self.stall_hysteresis_rad {
            Some((_, hi)) if alpha_rad > hi => true,
            Some((lo, _)) if alpha_rad < lo => false,
            Some(_) => latched,
            None => false,
        }
    }
}

/// Wind-axis coefficients with JSBSim's signs: drag positive aft, lift positive up, side positive
/// toward the right wing (body +y at β = 0).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Wind {
    pub drag: f32,
    pub side: f32,
    pub lift: f32,
}

/// Body-axis coefficients: JSBSim's `forces/fb{x,y,z}-aero-lbs` over `qbar·Sw` (x forward, y right,
/// z down; the normal-force coefficient is `−z`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Body {
    pub x: f32,
    pub y: f32,
    pub z: f32,
}

/// The force coefficients at one point and their analytic slopes in α and β (per radian).
///
/// The slopes are the exact derivatives of the interpolated model: within a table segment the
/// segment's slope; at an interior breakpoint the segment to its left (the one JSBSim interpolates
/// on there); zero at and beyond the end breakpoints, where JSBSim holds the end value. The body
/// slopes include the turning of `Tw2b` with α and β.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Coefficients {
    pub wind: Wind,
    pub body: Body,
    pub wind_d_alpha: Wind,
    pub wind_d_beta: Wind,
    pub body_d_alpha: Body,
    pub body_d_beta: Body,
    /// False when the inputs were not finite or the airspeed not positive: then everything is 0.
    pub valid: bool,
}

impl Model<'_> {
    /// Whether a lift term reads a trailing-edge surface: the aileron, the flaperon mix or the
    /// trailing-edge flap (what [`Model::trailing_edge_lift_body`] sums).
    pub fn reads_trailing_edge(t: &Term<'_>) -> bool {
        const TE: [Var; 4] = [
            Var::AileronRad,
            Var::LeftAileronRad,
            Var::FlaperonMixRad,
            Var::FlapDeg,
        ];
        t.factors.iter().any(|f| TE.iter().any(|v| f.reads(*v)))
    }

    /// The body-axis coefficient (x, y, z; over `qbar·Sw`) of the lift terms that read a
    /// trailing-edge surface ([`Model::reads_trailing_edge`]): what a trailing-edge lift scale
    /// multiplies. `None` if `p` or the sum is not finite.
    pub fn trailing_edge_lift_body(&self, p: &Point) -> Option<[f32; 3]> {
        if !p.is_finite() {
            return None;
        }
        let l = self
            .lift
            .iter()
            .filter(|t| Self::reads_trailing_edge(t))
            .fold(0.0, |acc, t| acc + t.partial(p).value);
        let (sa, ca) = (libm::sinf(p.alpha_rad), libm::cosf(p.alpha_rad));
        // Tw2b · (0, 0, −L): the lift's third column of Tw2b, independent of β.
        let b = [sa * l, 0.0, -ca * l];
        b.iter().all(|v| v.is_finite()).then_some(b)
    }

    pub fn coefficients(&self, air: &AirState, s: &Surfaces) -> Coefficients {
        match Point::new(self, air, s) {
            Some(p) => self.coefficients_at(&p),
            None => Coefficients::default(),
        }
    }

    fn axis(terms: &[Term<'_>], p: &Point) -> Partial {
        terms
            .iter()
            .fold(Partial::default(), |acc, t| acc.plus(t.partial(p)))
    }

    /// The coefficients at a point given in JSBSim's units.
    pub fn coefficients_at(&self, p: &Point) -> Coefficients {
        if !p.is_finite() {
            return Coefficients::default();
        }
        let (d, y, l) = (
            Self::axis(self.drag, p),
            Self::axis(self.side, p),
            Self::axis(self.lift, p),
        );
        let (sa, ca) = (libm::sinf(p.alpha_rad), libm::cosf(p.alpha_rad));
        let (sb, cb) = (libm::sinf(p.beta_rad), libm::cosf(p.beta_rad));
        // JSBSim: F_body = Tw2b · (−D, Y, −L), with
        //   Tw2b = [ ca·cb  −ca·sb  −sa ]
        //          [ sb      cb      0  ]
        //          [ sa·cb  −sa·sb   ca ]
        let tw2b = |m: [[f32; 3]; 3], w: [f32; 3]| -> [f32; 3] {
            let [r0, r1, r2] = m;
            let dot = |r: [f32; 3]| r[0] * w[0] + r[1] * w[1] + r[2] * w[2];
            [dot(r0), dot(r1), dot(r2)]
        };
        let m = [
            [ca * cb, -ca * sb, -sa],
            [sb, cb, 0.0],
            [sa * cb, -sa * sb, ca],
        ];
        let dm_da = [
            [-sa * cb, sa * sb, -ca],
            [0.0, 0.0, 0.0],
            [ca * cb, -ca * sb, -sa],
        ];
        let dm_db = [
            [-ca * sb, -ca * cb, 0.0],
            [cb, -sb, 0.0],
            [-sa * sb, -sa * cb, 0.0],
        ];
        let w = [-d.value, y.value, -l.value];
        let w_da = [-d.d_alpha, y.d_alpha, -l.d_alpha];
        let w_db = [-d.d_beta, y.d_beta, -l.d_beta];
        let add = |a: [f32; 3], b: [f32; 3]| [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
        let body = |v: [f32; 3]| Body {
            x: v[0],
            y: v[1],
            z: v[2],
        };
        let out = Coefficients {
            wind: Wind {
                drag: d.value,
                side: y.value,
                lift: l.value,
            },
            body: body(tw2b(m, w)),
            wind_d_alpha: Wind {
                drag: d.d_alpha,
                side: y.d_alpha,
                lift: l.d_alpha,
            },
            wind_d_beta: Wind {
                drag: d.d_beta,
                side: y.d_beta,
                lift: l.d_beta,
            },
            body_d_alpha: body(add(tw2b(dm_da, w), tw2b(m, w_da))),
            body_d_beta: body(add(tw2b(dm_db, w), tw2b(m, w_db))),
            valid: true,
        };
        if out.is_finite() {
            out
        } else {
            Coefficients::default()
        }
    }
}

impl Coefficients {
    fn is_finite(&self) -> bool {
        let w = |w: &Wind| [w.drag, w.side, w.lift];
        let b = |b: &Body| [b.x, b.y, b.z];
        [
            w(&self.wind),
            w(&self.wind_d_alpha),
            w(&self.wind_d_beta),
            b(&self.body),
            b(&self.body_d_alpha),
            b(&self.body_d_beta),
        ]
        .iter()
        .flatten()
        .all(|v| v.is_finite())
    }
}

/// Strictly ascending, so every table span is positive: asserted at compile time for each
/// generated table.
pub const fn strictly_ascending(mut x: &[f32]) -> bool {
    while let [a, b, ..] = x {
        // Not `a >= b`: a NaN must fail too.
        let ascending = *a < *b;
        if !ascending {
            return false;
        }
        x = match x {
            [_, rest @ ..] => rest,
            [] => return true,
        };
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(alpha_rad: f32, beta_rad: f32) -> Point {
        Point {
            alpha_rad,
            beta_rad,
            mach: 0.7,
            elevator_rad: -0.05,
            aileron_rad: 0.1,
            rudder_rad: -0.05,
            lef_rad: 0.2,
            speedbrake_rad: 0.3,
            flaperon_mix_rad: -0.2,
            gear_norm: 0.0,
            p_aero_rps: 0.5,
            q_aero_rps: 0.2,
            r_aero_rps: -0.1,
            bi2vel_s: 0.05,
            ci2vel_s: 0.02,
            h_over_b: 0.5,
            mag_beta_rad: beta_rad.abs(),
            mag_elevator_rad: 0.05,
            left_aileron_rad: 0.1,
            alpha_dot_rps: 0.05,
            flap_deg: 10.0,
            stall_hyst_norm: 0.0,
            slipstream_qbar_ratio: 1.0,
        }
    }

    #[test]
    fn the_trailing_edge_lift_is_that_of_the_lift_terms_reading_a_trailing_edge_surface() {
        let te = [Factor::Const(0.5), Factor::Var(Var::FlaperonMixRad)];
        let plain = [Factor::Const(2.0), Factor::Var(Var::AlphaRad)];
        let lift = [
            Term {
                name: "te",
                factors: &te,
            },
            Term {
                name: "plain",
                factors: &plain,
            },
        ];
        let m = Model {
            drag: &[],
            side: &[],
            lift: &lift,
            wing_area_ft2: 1.0,
            wingspan_ft: 1.0,
            chord_ft: 1.0,
            flaperon_mix_gain: 1.0,
            stall_hysteresis_rad: None,
        };
        assert!(Model::reads_trailing_edge(&lift[0]) && !Model::reads_trailing_edge(&lift[1]));
        let p = at(0.1, 0.05);
        let [x, y, z] = m.trailing_edge_lift_body(&p).unwrap();
        // The body force of a model of that term alone, through the full wind-to-body turn.
        let alone = Model {
            lift: &lift[..1],
            ..m
        }
        .coefficients_at(&p);
        assert!(alone.valid && alone.wind.lift == 0.5 * -0.2);
        for (got, want) in [(x, alone.body.x), (y, alone.body.y), (z, alone.body.z)] {
            assert!((got - want).abs() < 1e-7, "{got} against {want}");
        }
        assert!(z > 0.0, "a negative lift pushes down (body +z)");
        // Not finite in, nothing out.
        assert_eq!(m.trailing_edge_lift_body(&at(f32::NAN, 0.0)), None);
    }

    #[test]
    fn magnitudes_read_the_absolute_value_with_the_sign_as_slope() {
        // |β| through a 1-D table: the value of |β|, the table's slope times β's sign in β.
        let t = Table1 {
            key: Var::MagBetaRad,
            x: [0.0, 0.2],
            y: [0.0, 0.4],
        };
        for (beta, slope) in [(0.1f32, 2.0f32), (-0.1, -2.0)] {
            let v = t.look_up(&at(0.05, beta), sealed::Token);
            assert!((v.value - 0.2).abs() < 1e-6, "{beta}: {v:?}");
            assert!(
                (v.d_beta - slope).abs() < 1e-5 && v.d_alpha == 0.0,
                "{beta}: {v:?}"
            );
        }
        let p = at(0.05, -0.1);
        assert_eq!(p.get(Var::MagElevatorRad), 0.05);
        assert_eq!(
            Factor::Var(Var::MagBetaRad).eval(&p),
            Partial {
                value: 0.1,
                d_alpha: 0.0,
                d_beta: -1.0
            }
        );
        assert_eq!((p.get(Var::FlapDeg), p.get(Var::AlphaDotRps)), (10.0, 0.05));
    }

    #[test]
    fn one_d_lookup_is_jsbsims() {
        let t = Table1 {
            key: Var::AlphaRad,
            x: [0.0, 0.1, 0.3],
            y: [1.0, 2.0, 0.0],
        };
        let look = |a: f32| t.look_up(&at(a, 0.0), sealed::Token);
        // The end values themselves at and beyond the ends, with no slope.
        for (a, v) in [(-1.0, 1.0), (0.0, 1.0), (0.3, 0.0), (5.0, 0.0)] {
            assert_eq!(
                look(a),
                Partial::through(&at(a, 0.0), Var::AlphaRad, v, 0.0),
                "{a}"
            );
        }
        let m = look(0.05);
        assert!((m.value - 1.5).abs() < 1e-6 && (m.d_alpha - 10.0).abs() < 1e-4);
        // At an interior breakpoint: the value there, the slope of the segment to its left.
        let b = look(0.1);
        assert!((b.value - 2.0).abs() < 1e-6 && (b.d_alpha - 10.0).abs() < 1e-4);
        assert!((look(0.2).d_alpha + 10.0).abs() < 1e-4);
        assert_eq!(look(0.2).d_beta, 0.0);
    }

    #[test]
    fn two_d_lookup_is_bilinear_and_clamped() {
        let t = Table2 {
            row: Var::AlphaRad,
            col: Var::BetaRad,
            rows: [0.0, 1.0],
            cols: [0.0, 2.0, 4.0],
            data: [[0.0, 2.0, 2.0], [1.0, 5.0, 9.0]],
        };
        let look = |a: f32, b: f32| t.look_up(&at(a, b), sealed::Token);
        let p = look(0.5, 1.0);
        // Row blend: (0.5, 3.5) at cols 0 and 2; column blend halfway: 2.0.
        assert!((p.value - 2.0).abs() < 1e-6, "{p:?}");
        assert!(
            (p.d_alpha - 2.0).abs() < 1e-5 && (p.d_beta - 1.5).abs() < 1e-5,
            "{p:?}"
        );
        // Beyond the ends both fractions clamp: the corner value, no slopes.
        assert_eq!(look(-3.0, 9.0).value, 2.0);
        assert_eq!(
            (look(-3.0, 9.0).d_alpha, look(-3.0, 9.0).d_beta),
            (0.0, 0.0)
        );
        assert_eq!(look(7.0, -1.0).value, 1.0);
    }

    /// The analytic slopes against differences over α from −10° to 43° (60 points) and β from −9° to 11°: a
    /// one-sided difference, forward or backward, whichever stays inside the tables' segments (a
    /// breakpoint may lie on one side of the point, never on both within the step).
    #[test]
    fn slopes_are_the_derivatives_of_the_model() {
        let h = 1e-3_f32;
        for i in 0..60 {
            // A stride of no breakpoint spacing, so the points fall anywhere in the segments.
            let a = -0.175 + 0.0155 * i as f32;
            let b = [-0.15_f32, -0.02, 0.0, 0.07, 0.2][i % 5];
            let c = MODEL.coefficients_at(&at(a, b));
            assert!(c.valid);
            let all = |c: &Coefficients, d: &dyn Fn(&Coefficients) -> (Wind, Body)| {
                let (w, b) = d(c);
                [w.drag, w.side, w.lift, b.x, b.y, b.z]
            };
            let value = |c: &Coefficients| (c.wind, c.body);
            for (what, da, db, slope) in [
                ("alpha", h, 0.0, (c.wind_d_alpha, c.body_d_alpha)),
                ("beta", 0.0, h, (c.wind_d_beta, c.body_d_beta)),
            ] {
                let at_step =
                    |s: f32| all(&MODEL.coefficients_at(&at(a + s * da, b + s * db)), &value);
                let (here, analytic) = (all(&c, &value), all(&c, &|_| slope));
                let steps = [-1.0, -0.5, 0.5, 1.0].map(at_step);
                for k in 0..6 {
                    // Central, and the one-sided differences of second order (Richardson: twice
                    // the half step's less the whole step's).
                    let d = |s: f32, i: usize| (steps[i][k] - here[k]) / (s * h);
                    let central = (steps[3][k] - steps[0][k]) / (2.0 * h);
                    let fwd = 2.0 * d(0.5, 2) - d(1.0, 3);
                    let bwd = 2.0 * d(-0.5, 1) - d(-1.0, 0);
                    let x = analytic[k];
                    let near = |y: f32| (x - y).abs() <= 2e-3 * (1.0 + y.abs());
                    assert!(
                        near(central) || near(fwd) || near(bwd),
                        "d/d{what} component {k} at α {a} β {b}: analytic {x}, differences {central} / {fwd} / {bwd}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_stall_latch_sets_above_the_upper_limit_and_clears_below_the_lower() {
        let m = Model {
            stall_hysteresis_rad: Some((0.09, 0.36)),
            ..MODEL
        };
        let mut latched = false;
        let mut seen = [false; 6];
        for (i, a) in [0.2, 0.37, 0.2, 0.1, 0.08, 0.2].into_iter().enumerate() {
            latched = m.stall_latch(latched, a);
            seen[i] = latched;
        }
        assert_eq!(seen, [false, true, true, true, false, false]);
        assert!(m.stall_latch(true, f32::NAN));
        let none = Model {
            stall_hysteresis_rad: None,
            ..MODEL
        };
        assert!(!none.stall_latch(true, 0.5));
    }

    #[test]
    fn bad_inputs_give_zeros_and_invalid() {
        let air = AirState {
            alpha_rad: 0.1,
            beta_rad: 0.0,
            mach: 0.6,
            tas_mps: 200.0,
            p_rps: 0.0,
            q_rps: 0.0,
            r_rps: 0.0,
            h_over_b: AirState::NO_GROUND_EFFECT,
            unsteady: Unsteady::default(),
        };
        let s = Surfaces::default();
        assert!(MODEL.coefficients(&air, &s).valid);
        for bad in [
            AirState {
                alpha_rad: f32::NAN,
                ..air
            },
            AirState {
                beta_rad: f32::INFINITY,
                ..air
            },
            AirState {
                tas_mps: 0.0,
                ..air
            },
            AirState {
                tas_mps: -3.0,
                ..air
            },
            AirState {
                q_rps: f32::NEG_INFINITY,
                ..air
            },
            AirState {
                unsteady: Unsteady {
                    alpha_dot_rps: f32::NAN,
                    stall_latched: false,
                },
                ..air
            },
            // Finite but overflowing: q·c/(2V) is +Inf in f32.
            AirState {
                tas_mps: 1e-38,
                q_rps: 1e30,
                ..air
            },
        ] {
            assert_eq!(
                MODEL.coefficients(&bad, &s),
                Coefficients::default(),
                "{bad:?}"
            );
        }
        let nan_surface = Surfaces {
            elevator_deg: f32::NAN,
            ..s
        };
        assert_eq!(
            MODEL.coefficients(&air, &nan_surface),
            Coefficients::default()
        );
        let p = Point {
            mach: f32::NAN,
            ..at(0.1, 0.0)
        };
        assert_eq!(MODEL.coefficients_at(&p), Coefficients::default());
        assert!(MODEL.lift.iter().all(|t| t.eval(&p).is_none()));
    }

    #[test]
    fn breakpoint_check_sees_order() {
        assert!(strictly_ascending(&[0.0, 1.0, 2.0]));
        assert!(!strictly_ascending(&[0.0, 1.0, 1.0]));
        assert!(!strictly_ascending(&[0.0, f32::NAN]));
        assert!(strictly_ascending(&[]) && strictly_ascending(&[3.0]));
    }
}
