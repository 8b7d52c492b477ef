//! An aircraft's engines as JSBSim flies them, for their thrust along body x: a turbine's deck
//! (`FGTurbine::Run`: the thrust from the core speed N2, the throttle position, Mach and density
//! altitude) or a fixed-pitch propeller (`FGPropeller::Calculate`: the thrust from the propeller's
//! speed, the axial airspeed and the air density). Flight-test calibration computes the thrust
//! with it from the recorded engine channels, to tell the drag from the thrust along body x; the
//! flight software reads none of it.

use super::segment;

/// One of the deck's tables over Mach (rows) × density altitude in ft (columns), looked up as
/// JSBSim's `FGTable` does (linear between breakpoints, the end values beyond them, the row blended
/// first).
#[derive(Clone, Debug, PartialEq)]
pub struct EngineTable<const R: usize, const C: usize> {
    pub mach: [f32; R],
    pub density_altitude_ft: [f32; C],
    pub data: [[f32; C]; R],
}

/// What the deck needs of a table: its value at a Mach and density altitude (`None` if either is
/// not finite).
pub trait EngineLookup: Sync {
    fn at(&self, mach: f32, density_altitude_ft: f32) -> Option<f32>;
}

impl<const R: usize, const C: usize> EngineLookup for EngineTable<R, C> {
    fn at(&self, mach: f32, density_altitude_ft: f32) -> Option<f32> {
        if !(mach.is_finite() && density_altitude_ft.is_finite()) {
            return None;
        }
        let (r, rf, _) = segment(&self.mach, mach)?;
        let (c, cf, _) = segment(&self.density_altitude_ft, density_altitude_ft)?;
        let cell = |ri: usize, ci: usize| self.data.get(ri).and_then(|row| row.get(ci)).copied();
        let (r1, c1) = (r.wrapping_add(1), c.wrapping_add(1));
        let (a0, a1, b0, b1) = (cell(r, c)?, cell(r1, c)?, cell(r, c1)?, cell(r1, c1)?);
        let col1 = rf * a1 + (1.0 - rf) * a0;
        let col2 = rf * b1 + (1.0 - rf) * b0;
        Some(cf * (col2 - col1) + col1)
    }
}

/// How far below idle (N2, %) a recorded N2 may read and still be a running engine's: the gauge's
/// zero shift and noise.
pub const N2_BELOW_IDLE_PCT: f32 = 1.0;

/// An aircraft's engines, `count` alike, each thrusting along body x.
#[derive(Clone, Copy)]
pub enum Engine<'a> {
    /// JSBSim `<turbine_engine>`s with a direct thruster.
    Turbine(Turbine<'a>),
    /// Engines of any kind, each turning a fixed-pitch `<propeller>`.
    Propeller(Propeller<'a>),
}

impl Engine<'_> {
    /// How many engines the aircraft has.
    pub fn count(&self) -> u8 {
        match self {
            Engine::Turbine(t) => t.count,
            Engine::Propeller(p) => p.count,
        }
    }

    /// How far the thrust line lies below the aerodynamic reference point, m (the model's
    /// `AERORP` height less its thrusters'): the moment arm the thrust has about the reference
    /// point beyond the drag's.
    pub fn below_reference_m(&self) -> f32 {
        match self {
            Engine::Turbine(t) => t.below_reference_m,
            Engine::Propeller(p) => p.below_reference_m,
        }
    }
}

/// `count` JSBSim `<turbine_engine>`s of one deck, each with a direct thruster along body x.
#[derive(Clone, Copy)]
pub struct Turbine<'a> {
    /// How many engines of this deck the aircraft has.
    pub count: u8,
    /// `<milthrust>` and `<maxthrust>`, lbf.
    pub mil_thrust_lbf: f32,
    pub max_thrust_lbf: f32,
    /// `<idlen2>` and `<maxn2>`, %.
    pub idle_n2_pct: f32,
    pub max_n2_pct: f32,
    /// See [`Engine::below_reference_m`].
    pub below_reference_m: f32,
    /// `IdleThrust` (share of military thrust at idle), `MilThrust` (the military thrust's lapse)
    /// and, with an afterburner (`<augmethod>` 2), `AugThrust` (the maximum thrust's lapse).
    pub idle: &'a dyn EngineLookup,
    pub mil: &'a dyn EngineLookup,
    pub aug: Option<&'a dyn EngineLookup>,
}

impl Turbine<'_> {
    /// One engine's thrust, lbf, at core speed `n2_pct`, throttle position `throttle_pos` (above 1
    /// the afterburner's share), Mach and density altitude: `FGTurbine::Run` in its running phase,
    /// without bleed or water injection (`scripts/extract-aero` refuses a deck with either).
    /// `None` if an input is not finite, or N2 is more than [`N2_BELOW_IDLE_PCT`] below idle: a
    /// running engine never is, and a starting, windmilling or stopped one has no such thrust.
    pub fn thrust_lbf(
        &self,
        n2_pct: f32,
        throttle_pos: f32,
        mach: f32,
        density_altitude_ft: f32,
    ) -> Option<f32> {
        let running = n2_pct >= self.idle_n2_pct - N2_BELOW_IDLE_PCT;
        if !(n2_pct.is_finite() && throttle_pos.is_finite() && running)
            || self.max_n2_pct <= self.idle_n2_pct
        {
            return None;
        }
        let idle = self.mil_thrust_lbf * self.idle.at(mach, density_altitude_ft)?;
        let mil = (self.mil_thrust_lbf - idle) * self.mil.at(mach, density_altitude_ft)?;
        let n2_norm = (n2_pct - self.idle_n2_pct) / (self.max_n2_pct - self.idle_n2_pct);
        let mut thrust = idle + mil * n2_norm * n2_norm;
        let augment = throttle_pos - 1.0;
        if let Some(aug) = self.aug.filter(|_| augment > 0.0) {
            let max = self.max_thrust_lbf * aug.at(mach, density_altitude_ft)?;
            thrust += (max - thrust) * augment.min(1.0);
        }
        Some(thrust)
    }
}

/// One of a propeller's 1-D tables, looked up as JSBSim's `FGTable` does: `C_THRUST` (the thrust
/// coefficient C_T over the advance ratio J) or `CT_MACH` (C_T's factor over the helical tip Mach).
#[derive(Clone, Debug, PartialEq)]
pub struct PropellerTable<const N: usize> {
    pub x: [f32; N],
    pub y: [f32; N],
}

/// What a propeller needs of a table: its value at a key (`None` if the key is not finite).
pub trait PropellerLookup: Sync {
    fn at(&self, x: f32) -> Option<f32>;
}

impl<const N: usize> PropellerLookup for PropellerTable<N> {
    fn at(&self, x: f32) -> Option<f32> {
        if !x.is_finite() {
            return None;
        }
        let (i, f, _) = segment(&self.x, x)?;
        let y0 = *self.y.get(i)?;
        let y1 = *self.y.get(i.wrapping_add(1))?;
        Some(y0 + f * (y1 - y0))
    }
}

/// `count` engines of one kind, each turning a fixed-pitch JSBSim `<propeller>` whose thrust line
/// is body x.
#[derive(Clone, Copy)]
pub struct Propeller<'a> {
    /// How many engines and propellers the aircraft has.
    pub count: u8,
    /// `<diameter>`, ft.
    pub diameter_ft: f32,
    /// `<ct_factor>` (1 where the file has none).
    pub ct_factor: f32,
    /// See [`Engine::below_reference_m`].
    pub below_reference_m: f32,
    /// `C_THRUST`.
    pub thrust_coefficient: &'a dyn PropellerLookup,
    /// `CT_MACH`, where the file has one.
    pub tip_mach_factor: Option<&'a dyn PropellerLookup>,
}

impl Propeller<'_> {
    /// One propeller's thrust, lbf, at `rpm` (the propeller's own speed), the airspeed along its
    /// axis `axial_fps`, the air density `rho_slug_ft3` and the speed of sound `sound_fps`:
    /// `FGPropeller::Calculate`, C_T(J)·n²·D⁴·ρ with n in revolutions per second and J = V/(n·D)
    /// (V/D below 0.01 rev/s), C_T times `CT_MACH` at the helical tip Mach √((π·n·D)² + V²)/a.
    /// `None` if an input is not finite, the speed or density is negative, or the speed of sound
    /// is not positive.
    pub fn thrust_lbf(
        &self,
        rpm: f32,
        axial_fps: f32,
        rho_slug_ft3: f32,
        sound_fps: f32,
    ) -> Option<f32> {
        let finite = [rpm, axial_fps, rho_slug_ft3, sound_fps]
            .iter()
            .all(|v| v.is_finite());
        if !finite || rpm < 0.0 || rho_slug_ft3 < 0.0 || sound_fps <= 0.0 {
            return None;
        }
        let d = self.diameter_ft;
        let n = rpm / 60.0;
        let j = if n > 0.01 {
            axial_fps / (d * n)
        } else {
            axial_fps / d
        };
        let mut ct = self.thrust_coefficient.at(j)? * self.ct_factor;
        if let Some(mach) = self.tip_mach_factor {
            let tip = core::f32::consts::PI * n * d;
            ct *= mach.at(libm::sqrtf(tip * tip + axial_fps * axial_fps) / sound_fps)?;
        }
        Some(ct * n * n * d * d * d * d * rho_slug_ft3)
    }

    /// The velocity the propeller induces in its disc, ft/s, at thrust `thrust_lbf`, the airspeed
    /// along its axis `axial_fps` and the density `rho_slug_ft3`: JSBSim's momentum theory
    /// (`FGPropeller::Calculate`, McCormick), ½·(−V ± √(±(V·|V| + 2·T/(ρ·A)))) with A the disc's
    /// area, the signs those of the root's argument. `None` if an input is not finite or the
    /// density is not positive.
    pub fn induced_fps(&self, thrust_lbf: f32, axial_fps: f32, rho_slug_ft3: f32) -> Option<f32> {
        if !(thrust_lbf.is_finite() && axial_fps.is_finite() && rho_slug_ft3 > 0.0) {
            return None;
        }
        let area = 0.25 * self.diameter_ft * self.diameter_ft * core::f32::consts::PI;
        let sum = axial_fps * libm::fabsf(axial_fps) + 2.0 * thrust_lbf / (rho_slug_ft3 * area);
        let v = if sum > 0.0 {
            0.5 * (-axial_fps + libm::sqrtf(sum))
        } else {
            0.5 * (-axial_fps - libm::sqrtf(-sum))
        };
        v.is_finite().then_some(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    static FLAT: EngineTable<2, 2> = EngineTable {
        mach: [0.0, 1.0],
        density_altitude_ft: [0.0, 10_000.0],
        data: [[0.1, 0.2], [0.3, 0.4]],
    };
    static ONE: EngineTable<2, 2> = EngineTable {
        mach: [0.0, 1.0],
        density_altitude_ft: [0.0, 10_000.0],
        data: [[1.0, 1.0], [1.0, 1.0]],
    };

    #[test]
    fn tables_blend_the_row_first_and_hold_their_ends() {
        assert_eq!(FLAT.at(0.5, 5_000.0), Some(0.25));
        assert_eq!(FLAT.at(-1.0, -5.0), Some(0.1));
        assert_eq!(FLAT.at(2.0, 20_000.0), Some(0.4));
        assert_eq!(FLAT.at(f32::NAN, 0.0), None);
    }

    #[test]
    fn thrust_is_idle_plus_military_by_n2_squared_and_the_afterburner_blends_to_maximum() {
        let e = Turbine {
            count: 1,
            mil_thrust_lbf: 10_000.0,
            max_thrust_lbf: 15_000.0,
            idle_n2_pct: 60.0,
            max_n2_pct: 100.0,
            below_reference_m: 0.0,
            idle: &FLAT,
            mil: &ONE,
            aug: Some(&ONE),
        };
        // Idle 10,000·0.1 = 1,000 lbf; military adds (10,000 − 1,000)·1 at N2 = 100 %.
        assert_eq!(e.thrust_lbf(60.0, 0.0, 0.0, 0.0), Some(1_000.0));
        assert_eq!(e.thrust_lbf(100.0, 1.0, 0.0, 0.0), Some(10_000.0));
        assert_eq!(
            e.thrust_lbf(80.0, 0.5, 0.0, 0.0),
            Some(1_000.0 + 9_000.0 * 0.25)
        );
        // Half afterburner: halfway from military to 15,000 lbf; full beyond 2.
        assert_eq!(e.thrust_lbf(100.0, 1.5, 0.0, 0.0), Some(12_500.0));
        assert_eq!(e.thrust_lbf(100.0, 2.5, 0.0, 0.0), Some(15_000.0));
        assert_eq!(e.thrust_lbf(f32::NAN, 1.0, 0.0, 0.0), None);
        // Below idle by more than the gauge's error: not a running engine.
        assert_eq!(
            e.thrust_lbf(59.5, 0.0, 0.0, 0.0),
            Some(1_000.0 + 9_000.0 * (0.5f32 / 40.0).powi(2))
        );
        assert_eq!(e.thrust_lbf(58.9, 0.0, 0.0, 0.0), None);
        let dry = Turbine { aug: None, ..e };
        assert_eq!(dry.thrust_lbf(100.0, 1.5, 0.0, 0.0), Some(10_000.0));
        assert_eq!(Engine::Turbine(e).count(), 1);
    }

    static CT: PropellerTable<3> = PropellerTable {
        x: [0.0, 1.0, 2.0],
        y: [0.1, 0.05, -0.05],
    };
    static TIP: PropellerTable<2> = PropellerTable {
        x: [0.85, 1.05],
        y: [1.0, 0.8],
    };

    #[test]
    fn propeller_thrust_is_ct_of_the_advance_ratio_times_n_squared_d4_rho() {
        let p = Propeller {
            count: 2,
            diameter_ft: 2.0,
            ct_factor: 1.0,
            below_reference_m: 0.5,
            thrust_coefficient: &CT,
            tip_mach_factor: Some(&TIP),
        };
        let a = 1_000.0;
        let near = |got: Option<f32>, want: f32| {
            got.is_some_and(|t| (t - want).abs() <= 1e-6 * want.abs().max(1.0))
        };
        // 600 rpm: n = 10 rev/s; 10 ft/s over n·D = 20 ft is J 0.5, C_T 0.075;
        // 0.075·100·16·0.002 = 0.24 lbf.
        assert!(near(p.thrust_lbf(600.0, 10.0, 0.002, a), 0.24));
        // J beyond the table holds its end (a windmilling propeller's drag).
        assert!(near(p.thrust_lbf(600.0, 100.0, 0.002, a), -0.16));
        let scaled = Propeller {
            ct_factor: 1.1,
            ..p
        };
        assert!(near(scaled.thrust_lbf(600.0, 10.0, 0.002, a), 0.264));
        // A stopped propeller: J = V/D, times n² = 0.
        assert_eq!(p.thrust_lbf(0.0, 10.0, 0.002, a), Some(0.0));
        assert_eq!(p.thrust_lbf(f32::NAN, 10.0, 0.002, a), None);
        assert_eq!(p.thrust_lbf(600.0, f32::INFINITY, 0.002, a), None);
        assert_eq!(p.thrust_lbf(-1.0, 10.0, 0.002, a), None);
        // A helical tip Mach of 0.95 (the tip alone: no axial speed) takes C_T times 0.9.
        let rpm = 0.95 * a / (core::f32::consts::PI * 2.0) * 60.0;
        let n = rpm / 60.0;
        let want = 0.1 * 0.9 * n * n * 16.0 * 0.002;
        assert!(near(p.thrust_lbf(rpm, 0.0, 0.002, a), want));
        assert_eq!(p.thrust_lbf(600.0, 10.0, 0.002, 0.0), None);
        assert_eq!(Engine::Propeller(p).count(), 2);
        assert_eq!(Engine::Propeller(p).below_reference_m(), 0.5);
        // Momentum theory: 2·T/(ρ·A) = V_i² + V·V_i·2 … at V = 10 ft/s and T = 0.24 lbf over the
        // 2-ft disc (A = π ft²): ½·(−10 + √(100 + 0.48/(0.002·π))).
        let want = 0.5 * (-10.0 + libm::sqrtf(100.0 + 0.48 / (0.002 * core::f32::consts::PI)));
        assert!(near(p.induced_fps(0.24, 10.0, 0.002), want));
        // No thrust, no induced velocity; a windmilling propeller's is negative.
        assert!(near(p.induced_fps(0.0, 10.0, 0.002), 0.0));
        assert!(p.induced_fps(-0.16, 10.0, 0.002).is_some_and(|v| v < 0.0));
        assert_eq!(p.induced_fps(0.24, 10.0, 0.0), None);
    }
}
