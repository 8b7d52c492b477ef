//! Flying a runscript with sensors: the plant (JSBSim through the bridge) steps at 120 Hz, every
//! step feeds the sensor models, and every sixth step becomes a 20 Hz sample of truth and sensed
//! values (`plant -> sensors -> flight record`).

use std::path::Path;

use crate::flight::{
    Every, FT_TO_M, Flight, LB_TO_KG, NO_SUBSAMPLES, SIM_HZ, STEPS_PER_SAMPLE, Sample, Zone,
    ZoneTimes,
};
use crate::plant::{
    AIRBORNE_AGL_FT, GROUND_CUT_AGL_FT, Loaded, OPTIONAL, Plant, PlantError, ReadPlan, TRUTH_ONLY,
    WATCH, at, engine_of, load_runscript, truth_of,
};
use crate::sensors::{InputSchedule, SensorConfig, SensorInput, SensorModel};

/// Settings of one flight.
#[derive(Clone, Debug, Default)]
pub struct FlyConfig {
    /// Seed of the sensor error models.
    pub seed: u64,
    pub sensors: SensorConfig,
    /// Stop after this much simulated time even if the script goes on.
    pub max_time_s: Option<f64>,
    /// Name stored with the flight (default: the script file stem).
    pub name: Option<String>,
    /// The JSBSim aircraft directory whose `MODEL/MODEL.xml` (the build's aircraft's) is flown
    /// (`--aircraft-dir`); `None`: the jsbsim package's own.
    pub aircraft_dir: Option<std::path::PathBuf>,
}

/// What the sensors see at one step, in SI (surfaces in degrees).
fn sensor_input(r: &[f64]) -> SensorInput {
    let m = r[at::MASS];
    SensorInput {
        omega_rps: [r[at::PI], r[at::QI], r[at::RI]],
        omega_dot_rps2: [r[at::PDOT], r[at::QDOT], r[at::RDOT]],
        // Specific force at the CG: total non-gravity force over mass (not accelerations/N*, which lag a step).
        f_cg_mps2: [
            r[at::FBX] / m * FT_TO_M,
            r[at::FBY] / m * FT_TO_M,
            r[at::FBZ] / m * FT_TO_M,
        ],
        gps_speed_mps: r[at::GPS_SPEED] * FT_TO_M,
        alt_msl_m: r[at::H_SL] * FT_TO_M,
        surfaces_deg: std::array::from_fn(|i| {
            match estimator_core::aircraft::AIRCRAFT.surfaces[i] {
                Some(s) => r[at::SURFACES + i] * s.deg_per_unit,
                None => 0.0,
            }
        }),
        throttle_norm: r[at::THROTTLE],
        euler_rad: [r[at::PHI], r[at::THETA], r[at::PSI]],
        omega_earth_rps: [r[at::P], r[at::Q], r[at::R]],
        v_ned_mps: [
            r[at::V_NORTH] * FT_TO_M,
            r[at::V_EAST] * FT_TO_M,
            r[at::V_DOWN] * FT_TO_M,
        ],
        fuel_kg: r[at::FUEL] * LB_TO_KG,
    }
}

/// The steps (from 0 after the load) that become 20 Hz samples: every sixth, the first at step 5.
const SAMPLE_STEPS: Every = Every {
    period: STEPS_PER_SAMPLE as u64,
    offset: STEPS_PER_SAMPLE as u64 - 1,
};

/// When each [`WATCH`] property is read: the truth at the samples ([`truth_of`]); the sensor inputs
/// that the models use only at some steps ([`InputSchedule`]) there and at the samples; everything
/// else (the IMU's inputs, the surfaces, mass, the ground check, the zone) at every step. The
/// rows then hold exactly what a read at every step would give wherever it is used, so the
/// flight is the same bit for bit (`tests::a_planned_flight_is_the_every_step_flight_bit_for_bit`;
/// the sensors' own schedule: `sensors::tests::inputs_off_their_schedule_change_no_output_bit`).
fn read_plan(s: &InputSchedule) -> ReadPlan {
    let mut when: Vec<Option<Vec<Every>>> = vec![None; at::COUNT];
    let mut set = |i: usize, steps: &[Every]| {
        if let Some(w) = when.get_mut(i) {
            *w = Some(steps.iter().copied().chain([SAMPLE_STEPS]).collect());
        }
    };
    for i in TRUTH_ONLY {
        set(i, &[]);
    }
    set(at::GPS_SPEED, &[s.gps]);
    set(at::H_SL, &[s.gps]);
    set(at::PHI, &[s.attitude, s.egi_velocity]);
    set(at::THETA, &[s.attitude, s.egi_velocity]);
    set(at::PSI, &[s.heading, s.egi_velocity]);
    for i in [at::P, at::Q, at::R, at::V_NORTH, at::V_EAST, at::V_DOWN] {
        set(i, &[s.egi_velocity]);
    }
    set(at::FUEL, &[s.fuel]);
    ReadPlan::new(&when)
}

/// Flies a JSBSim runscript (of the build's aircraft) to its end (or `cfg.max_time_s`) at 120 Hz and returns
/// the 20 Hz flight. The initialize file is taken from beside the script when it is there, else
/// JSBSim looks in the aircraft folder (where the stock `reset*` files live). A flight that hits the
/// ground or goes NaN is cut there and says so in [`Flight::cut`].
pub fn fly_script(script: &Path, cfg: &FlyConfig) -> Result<Flight, PlantError> {
    let mut plant = Plant::spawn_for(cfg.aircraft_dir.as_deref())?;
    fly_script_with(&mut plant, script, cfg)
}

/// [`fly_script`] on an already started bridge (one process per flight keeps flights independent;
/// callers that want that start a fresh [`Plant`] each time).
pub fn fly_script_with(
    plant: &mut Plant,
    script: &Path,
    cfg: &FlyConfig,
) -> Result<Flight, PlantError> {
    fly_planned(plant, script, cfg, read_plan)
}

/// [`fly_script_with`], each property read where `plan` says.
fn fly_planned(
    plant: &mut Plant,
    script: &Path,
    cfg: &FlyConfig,
    plan: fn(&InputSchedule) -> ReadPlan,
) -> Result<Flight, PlantError> {
    let Loaded { path: script, dt_s } = load_runscript(plant, script)?;
    let mut sensors = SensorModel::new(&cfg.sensors, cfg.seed);
    let plan = plan(&sensors.input_schedule());
    plant.watch_planned(&WATCH, &plan)?;
    let name = cfg.name.clone().unwrap_or_else(|| {
        script
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "flight".into())
    });
    let mut flight = Flight {
        name,
        samples: Vec::new(),
        cut: None,
        zones: None,
        engine: Vec::new(),
    };
    // Steps since the load, counted from 0 as the read plan counts them.
    let mut k: u64 = 0;
    let mut zone_steps: Option<[u64; 3]> = None;
    let mut airborne = false;
    // The sensors' 120 Hz outputs of the last `SUBSAMPLES` steps, oldest first.
    let mut sub = NO_SUBSAMPLES;
    'outer: loop {
        let rows = plant.step(SIM_HZ * 5)?;
        let ended = rows.len() < (SIM_HZ * 5) as usize;
        for r in &rows {
            let read = plan.at(k);
            let sample_step = SAMPLE_STEPS.contains(k);
            k += 1;
            let t = r[at::TIME];
            if cfg.max_time_s.is_some_and(|max| t > max + 1e-9) {
                break 'outer;
            }
            // The optional properties ([`OPTIONAL`]) are not checked; the properties not read at
            // this step are NaN and are checked where they are read (a diverging JSBSim state
            // shows first in the forces and rates, read at every step).
            if r.iter()
                .zip(read)
                .zip(OPTIONAL)
                .any(|((v, read), optional)| *read && !optional && !v.is_finite())
            {
                flight.cut = Some(format!("non-finite JSBSim state at t={t:.3} s"));
                break 'outer;
            }
            airborne |= r[at::H_AGL] > AIRBORNE_AGL_FT;
            if airborne && r[at::H_AGL] < GROUND_CUT_AGL_FT {
                flight.cut = Some(format!(
                    "ground contact at t={t:.3} s (h-agl {:.1} ft)",
                    r[at::H_AGL]
                ));
                break 'outer;
            }
            if let Some(zone) = Zone::from_value(r[at::ZONE]) {
                let n = zone_steps.get_or_insert([0; 3]);
                n[zone.index()] += 1;
            }
            let si = sensors.step(&sensor_input(r));
            sub.rotate_left(1);
            if let Some(last) = sub.last_mut() {
                *last = sensors.fast_output();
            }
            if sample_step {
                flight.samples.push(Sample {
                    // JSBSim's own clock (its summed dt, e.g. 0.049999999999999996 after 6 steps):
                    // the instants a stock run reports, so truth can be compared sample by sample.
                    time_s: t,
                    truth: truth_of(r),
                    sensed: si,
                    sub,
                });
                flight.engine.push(engine_of(r));
            }
        }
        if ended {
            break;
        }
    }
    flight.zones = zone_steps.map(|n| ZoneTimes::from_steps(n, dt_s));
    Ok(flight)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 30 s of the build's aircraft's stock test flight (`flights/NAME_test_flight.xml`: for the
    /// F-16 a climbing turn with its sensors' GPS fixes, EGI outputs and fuel updates), flown once
    /// reading only what the plan names and once reading every property at every step: every
    /// sample's truth and sensed values are the same bits. Moving any property of `read_plan` to a
    /// schedule that misses a step where it is used fails this.
    #[test]
    fn a_planned_flight_is_the_every_step_flight_bit_for_bit() {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!(
            "../flights/{}_test_flight.xml",
            estimator_core::aircraft::AIRCRAFT.name
        ));
        let cfg = FlyConfig {
            seed: 7,
            max_time_s: Some(30.0),
            ..FlyConfig::default()
        };
        let fly = |plan: fn(&InputSchedule) -> ReadPlan| {
            let mut plant = Plant::spawn().unwrap_or_else(|e| panic!("{e}"));
            fly_planned(&mut plant, &script, &cfg, plan).unwrap_or_else(|e| panic!("{e}"))
        };
        let (planned, full) = (fly(read_plan), fly(|_| ReadPlan::every_step(at::COUNT)));
        assert_eq!(planned.samples.len(), 600);
        assert_eq!(planned.cut, full.cut);
        assert_eq!(planned.engine, full.engine);
        for (k, (p, f)) in planned.samples.iter().zip(&full.samples).enumerate() {
            assert_eq!(p.time_s.to_bits(), f.time_s.to_bits(), "sample {k}");
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&p.truth.to_array()),
                bits(&f.truth.to_array()),
                "truth, sample {k}"
            );
            assert_eq!(bits(&p.sensed), bits(&f.sensed), "sensed, sample {k}");
            let sub = |s: &Sample| bits(s.sub.as_flattened());
            assert_eq!(sub(p), sub(f), "sub-samples, sample {k}");
        }
    }
}
