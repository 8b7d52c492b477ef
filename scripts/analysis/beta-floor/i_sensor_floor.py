"""Physics side of two small questions (no network): (1) how the turbulence floor moves with the IMU
anti-alias cut-off (F1-style linear deconvolution, fitted on the aggressive training flights);
(2) what the filter's gear-up assumption (CDgear = 0 while every flight has the gear down) does to
a β inverted from the true lateral force. (1) holds for any $AIRCRAFT; (2) uses the F-16's tables and is
skipped on another aircraft.
Needs: $WORK/replay/ of the test and the aggressive training flights (16 in `large`, 4 in `paper`).
usage: [AIRCRAFT=f15] nice -n 19 <repo>/.venv/bin/python i_sensor_floor.py > "$WORK/out/i_sensor_floor.md"
"""
import numpy as np
from common import AIRCRAFT, FT, beta_from_cy_body, flights, imu_filter_120, mae
from d_turb import parts
from f_floor import TESTS, lags
from frames import table

def prep(n, fcs):
    d = table(n)
    b_all, b_nt = parts(d)
    bt = b_all - b_nt
    i = d["idx120"]
    return d, b_all[i], b_nt[i], bt[i], {fc: imu_filter_120(bt, fc=fc)[i] for fc in fcs}

fcs = [6.0, 10.0, 15.0, 25.0]
train = [fl["name"] for fl in flights("train") if fl["profile"] == "aggressive"]
tr = [prep(n, fcs) for n in train]
te = {n: prep(n, fcs) for n in TESTS}
print(f"# (1) Turbulence floor vs IMU anti-alias cut-off (lag 3 ms kept), {AIRCRAFT}\n")
print(f"β_noturb exact + β_turb from its IMU-filtered samples: 'as filtered' (no deconvolution) / linear deconvolution, lags 0..5 (fit: {len(tr)} aggressive training flights).\n")
print("| cut-off | " + " | ".join(TESTS) + " |")
print("|---|" + "---|" * len(TESTS))
for fc in fcs:
    x = np.concatenate([np.stack(lags(p[4][fc], 5) + [np.ones_like(p[3])], 1) for p in tr])
    y = np.concatenate([p[3] for p in tr])
    w, *_ = np.linalg.lstsq(x, y, rcond=None)
    cells = []
    for n, p in te.items():
        raw = mae(p[2] + p[4][fc] - p[1])
        dec = mae(p[2] + np.stack(lags(p[4][fc], 5) + [np.ones_like(p[3])], 1) @ w - p[1])
        cells.append(f"{raw:.3f} / {dec:.3f}")
    print(f"| {fc:g} Hz | " + " | ".join(cells) + " |")

if AIRCRAFT != "f16":
    print("\n# (2) Gear: skipped (the F-16's tables and CDgear)")
    raise SystemExit(0)
print("\n# (2) Gear: every flight flies with the gear down (gear/gear-pos-norm = 1, CDgear = 0.027)\n")
print("β inverted from JSBSim's exact lateral force and aero rates (exact = 0) with the drag term lacking CDgear, as a gear-up model would.\n")
print("| flight | MAE of the β error | mean abs β | error / abs β |")
print("|---|---|---|---|")
for n in TESTS:
    r = te[n][0]["r120"]
    qs = r["aero__qbar_psf"] * 300
    cd = r["forces__fwx_aero_lbs"] / qs
    args = (r["forces__fby_aero_lbs"] / qs, r["aero__alpha_rad"], r["velocities__mach"], r["fcs__aileron_pos_rad"],
            r["fcs__rudder_pos_rad"], r["velocities__p_aero_rad_sec"], r["velocities__r_aero_rad_sec"], r["velocities__vt_fps"] * FT)
    b0 = beta_from_cy_body(*args, cd)
    b1 = beta_from_cy_body(*args, cd - 0.027)
    e = np.degrees(b1 - b0)
    print(f"| {n} | {mae(e):.4f} | {mae(np.degrees(b0)):.3f} | {mae(e)/mae(np.degrees(b0))*100:.1f} % |")
