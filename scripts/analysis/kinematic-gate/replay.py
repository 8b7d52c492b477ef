#!/usr/bin/env python3
"""The air-data filter's kinematic check replayed on a dataset's channels (docs/filter.md): per
flight, the largest 0.5-s running mean of the y and z accelerometer reading less the specific
force the EGI's velocity change and gravity give in body axes (the mean of the step's two EGI
attitude matrices, as the filter turns it), after the first 2 s. The EGI channels carry the IMU point's velocity, so the lever-arm terms the filter's
CG velocity leaves in its own residual are not in this one.

usage: .venv/bin/python scripts/analysis/kinematic-gate/replay.py [--mean-accel] DATA_DIR

--mean-accel compares the mean of the step's two accelerometer readings instead of the frame's
(the filter reads the frame's).
"""
import json
import os
import sys

import numpy as np

G = 9.80665
DT = 0.05
TAU_S = 0.5  # estimator_core::filter::KINEMATIC_TAU_S


def body_from_ned(phi, theta, psi):
    """Per frame, the NED → body direction-cosine matrix (as the filter's c_bn)."""
    cp, sp, ct, st, cs, ss = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta), np.cos(psi), np.sin(psi)
    nb = np.empty((len(phi), 3, 3))
    nb[:, 0, 0] = ct * cs
    nb[:, 0, 1] = sp * st * cs - cp * ss
    nb[:, 0, 2] = cp * st * cs + sp * ss
    nb[:, 1, 0] = ct * ss
    nb[:, 1, 1] = sp * st * ss + cp * cs
    nb[:, 1, 2] = cp * st * ss - sp * cs
    nb[:, 2, 0] = -st
    nb[:, 2, 1] = sp * ct
    nb[:, 2, 2] = cp * ct
    return np.transpose(nb, (0, 2, 1))


def largest(path, mean_accel):
    d = np.genfromtxt(path, delimiter=",", names=True)
    accel = np.stack([d["accel_x_mps2"], d["accel_y_mps2"], d["accel_z_mps2"]], 1)
    v = np.stack([d["egi_v_north_mps"], d["egi_v_east_mps"], d["egi_v_down_mps"]], 1)
    bn = body_from_ned(d["egi_roll_rad"], d["egi_pitch_rad"], d["egi_heading_rad"])
    a_ned = (v[1:] - v[:-1]) / DT - np.array([0.0, 0.0, G])
    if mean_accel:
        accel[1:] = 0.5 * (accel[1:] + accel[:-1])
    residual = accel[1:] - np.einsum("nij,nj->ni", 0.5 * (bn[1:] + bn[:-1]), a_ned)
    k = DT / (TAU_S + DT)
    mean = np.zeros(3)
    worst = np.zeros(3)
    for i, r in enumerate(residual):
        ok = np.isfinite(r)
        mean[ok] += k * (r[ok] - mean[ok])
        if i >= 40:
            worst = np.maximum(worst, np.abs(mean))
    return worst[1], worst[2]


def main():
    args = sys.argv[1:]
    mean_accel = args[:1] == ["--mean-accel"]
    args = args[1:] if mean_accel else args
    if len(args) != 1 or not os.path.isfile(os.path.join(args[0], "manifest.json")):
        sys.exit("usage: replay.py [--mean-accel] DATA_DIR (a hil-sim generate dataset)")
    # The manifest's flights (a flight-test dataset also holds each flight's boom record).
    with open(os.path.join(args[0], "manifest.json")) as f:
        files = sorted(fl["file"] for fl in json.load(f)["flights"])
    rows = [(name[:-4], *largest(os.path.join(args[0], name), mean_accel)) for name in files]
    y = max(rows, key=lambda r: r[1])
    z = max(rows, key=lambda r: r[2])
    print(f"{len(rows)} flights; largest running mean y {y[1]:.2f} m/s² ({y[0]}), z {z[2]:.2f} m/s² ({z[0]})")


if __name__ == "__main__":
    main()
