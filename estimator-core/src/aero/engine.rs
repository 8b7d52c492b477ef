//! A turbine engine's thrust deck as JSBSim flies it (`FGTurbine::Run`): the thrust from the
//! engine's core speed N2, its throttle position, Mach and density altitude. Flight-test
//! calibration computes the thrust with it from the recorded engine channels, to tell the drag
//! from the thrust along body x; the flight software reads none of it.

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

/// An aircraft's engines: `count` alike, each a JSBSim `<turbine_engine>` with a direct thruster
/// along body x.
#[derive(Clone, Copy)]
pub struct Engine<'a> {
    /// How many engines of this deck the aircraft has.
    pub count: u8,
    /// `<milthrust>` and `<maxthrust>`, lbf.
    pub mil_thrust_lbf: f32,
    pub max_thrust_lbf: f32,
    /// `<idlen2>` and `<maxn2>`, %.
    pub idle_n2_pct: f32,
    pub max_n2_pct: f32,
    /// `IdleThrust` (share of military thrust at idle), `MilThrust` (the military thrust's lapse)
    /// and, with an afterburner (`<augmethod>` 2), `AugThrust` (the maximum thrust's lapse).
    pub idle: &'a dyn EngineLookup,
    pub mil: &'a dyn EngineLookup,
    pub aug: Option<&'a dyn EngineLookup>,
}

impl Engine<'_> {
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
        let e = Engine {
            count: 1,
            mil_thrust_lbf: 10_000.0,
            max_thrust_lbf: 15_000.0,
            idle_n2_pct: 60.0,
            max_n2_pct: 100.0,
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
        let dry = Engine { aug: None, ..e };
        assert_eq!(dry.thrust_lbf(100.0, 1.5, 0.0, 0.0), Some(10_000.0));
    }
}
