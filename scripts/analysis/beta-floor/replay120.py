"""Re-fly a dataset flight's maneuver in stock JSBSim (the project's pinned .venv) and keep ~70
properties at every 120 Hz step: the aero side-force terms, turbulence, aero vs inertial rates,
forces. Analysis only (reads $DATA/<name>.xml and _init.xml, writes $WORK/replay/<name>.npz).
The script's aircraft must be $AIRCRAFT's JSBSim model (paths.py). The fcs/* and aero/coefficient/*
names below are the F-16's: on another aircraft those its model lacks are recorded as NaN; the
model's own β terms of side force and drag (common.beta_terms), its side force's aero-rate
terms (common.rate_terms) and its side force's sensed-surface terms with their surfaces
(common.surface_terms) are recorded on every aircraft.

usage: [AIRCRAFT=f15] nice -n 19 <repo>/.venv/bin/python replay120.py test_aggressive_03 [more names]
"""
import os
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np
import jsbsim

from common import AIRCRAFT, JSBSIM_MODEL, beta_terms, key, rate_terms, surface_terms
from paths import DATA, WORK

OUT = os.path.join(WORK, "replay")

PROPS = [
    "simulation/sim-time-sec",
    "aero/alpha-rad", "aero/beta-rad", "aero/qbar-psf", "velocities/vt-fps", "velocities/mach",
    "velocities/u-aero-fps", "velocities/v-aero-fps", "velocities/w-aero-fps",
    "forces/fbx-total-lbs", "forces/fby-total-lbs", "forces/fbz-total-lbs",
    "forces/fbx-aero-lbs", "forces/fby-aero-lbs", "forces/fbz-aero-lbs",
    "?forces/fby-prop-lbs", "?forces/fby-gear-lbs",
    "forces/fwx-aero-lbs", "forces/fwy-aero-lbs", "forces/fwz-aero-lbs",
    "inertia/mass-slugs",
    "velocities/p-aero-rad_sec", "velocities/q-aero-rad_sec", "velocities/r-aero-rad_sec",
    "velocities/p-rad_sec", "velocities/q-rad_sec", "velocities/r-rad_sec",
    "velocities/pi-rad_sec", "velocities/qi-rad_sec", "velocities/ri-rad_sec",
    "accelerations/pdot-rad_sec2", "accelerations/qdot-rad_sec2", "accelerations/rdot-rad_sec2",
    "atmosphere/p-turb-rad_sec", "atmosphere/q-turb-rad_sec", "atmosphere/r-turb-rad_sec",
    "atmosphere/turb-north-fps", "atmosphere/turb-east-fps", "atmosphere/turb-down-fps",
    "atmosphere/total-wind-north-fps", "atmosphere/total-wind-east-fps", "atmosphere/total-wind-down-fps",
    "atmosphere/wind-north-fps", "atmosphere/wind-east-fps",
    "atmosphere/turbulence/milspec/severity", "atmosphere/rho-slugs_ft3",
    "fcs/rudder-pos-rad", "fcs/aileron-pos-rad", "fcs/elevator-pos-rad",
    "fcs/speedbrake-pos-rad", "fcs/flaperon-mix-rad", "fcs/lef-pos-rad", "fcs/left-flaperon-norm", "fcs/tef-control",
    "accelerations/n-pilot-y-norm", "velocities/vg-fps",
    "aero/coefficient/CYb", "aero/coefficient/CYb_M", "aero/coefficient/CYDa",
    "aero/coefficient/CYdr", "aero/coefficient/CYp", "aero/coefficient/CYr",
    "aero/bi2vel",
    "attitude/phi-rad", "attitude/theta-rad", "attitude/psi-rad",
    "velocities/v-north-fps", "velocities/v-east-fps", "velocities/v-down-fps",
    "position/h-sl-ft",
    "?maneuver/zone",
]


def props():
    own = AIRCRAFT == "f16"
    out = [p if own or p.startswith("?") or not p.startswith(("fcs/", "aero/coefficient/")) else "?" + p
           for p in PROPS]
    terms = beta_terms()
    rates = rate_terms()
    surfaces = [x for t, prop, _, _ in surface_terms() for x in (t, prop)]
    extra = terms["SIDE"] + terms["DRAG"] + rates["p"] + rates["r"] + surfaces
    have = {p.lstrip("?") for p in out}
    return out + [p for p in dict.fromkeys(extra) if p not in have]


def main():
    os.makedirs(OUT, exist_ok=True)
    wanted = props()
    for name in sys.argv[1:]:
        t0 = time.time()
        script = os.path.join(DATA, name + ".xml")
        init = os.path.join(DATA, name + "_init.xml")
        flown = ET.parse(script).getroot().find("use").get("aircraft")
        if flown != JSBSIM_MODEL:
            raise SystemExit(f"{script} flies {flown}, not AIRCRAFT={AIRCRAFT} ({JSBSIM_MODEL}): set AIRCRAFT")
        fdm = jsbsim.FGFDMExec(jsbsim.get_default_root_dir())
        fdm.set_debug_level(0)
        if not fdm.load_script(script, 0.0, init):
            raise SystemExit("load failed")
        fdm.run_ic()
        pm = fdm.get_property_manager()
        getters = []
        for p in wanted:
            opt = p.startswith("?")
            n = pm.get_node(p[1:] if opt else p, False)
            if n is None:
                if not opt:
                    raise SystemExit("missing " + p)
                getters.append(lambda: float("nan"))
            else:
                getters.append(n.get_double_value)
        rows = []
        while fdm.run():
            rows.append([g() for g in getters])
        a = np.array(rows, dtype=np.float64 if name.startswith("test") else np.float32)
        keys = [key(p.lstrip("?")) for p in wanted]
        np.savez_compressed(os.path.join(OUT, name + ".npz"), **{k: a[:, i] for i, k in enumerate(keys)})
        print(f"{name}: {len(rows)} steps in {time.time() - t0:.1f} s", flush=True)


if __name__ == "__main__":
    main()
