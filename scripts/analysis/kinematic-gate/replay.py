#!/usr/bin/env python3
"""The air-data filter's kinematic check replayed on a dataset's channels (docs/filter.md): per
flight, the largest 0.5-s running mean of the y and z accelerometer reading less the specific
force the EGI's velocity change and gravity give in body axes (the mean of the step's two EGI
attitude matrices, as the filter turns it), each step's residual less the timing dead band as the
filter takes it off, after the first 2 s; in brackets without the dead band. The EGI channels
carry the IMU point's velocity and the accelerometers read the IMU's force, so there are no
lever-arm terms here (the filter moves both to the CG, and its band's ω × f takes the CG's force
where this one takes the IMU's). A step whose residual or band is not finite is not folded in, as
in the filter; the frames are taken as 0.05 s apart (the filter folds no step over 0.1 s).

The gyro check too: per flight, the largest 1-s running mean of each gyro (p, q, r) less the body
rate that turns one frame's EGI attitude into the next one's, from the first step, the gyro taken
as the filter takes it: over the newer half of the previous frame period and the older half of
this one (the 120 Hz sub-samples); in brackets from the 20 Hz gyros, three quarters this frame's
and a quarter the previous one's (the filter's way for frames without the sub-samples).

usage: .venv/bin/python scripts/analysis/kinematic-gate/replay.py DATA_DIR
"""
import json
import os
import sys

import numpy as np

G = 9.80665
DT = 0.05
TAU_S = 0.5  # estimator_core::filter::KINEMATIC_TAU_S
TIMING_S = 0.05  # estimator_core::filter::KINEMATIC_TIMING_S
GYRO_TAU_S = 1.0  # estimator_core::filter::GYRO_TAU_S
GYRO_20HZ_SHARE = 0.75  # estimator_core::filter::GYRO_20HZ_SHARE


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


def largest(path):
    """The flight's largest running mean of the y and z residual, with and without the dead band,
    and of the p, q and r gyro residual, from the sub-samples and from the 20 Hz gyros."""
    d = np.genfromtxt(path, delimiter=",", names=True)
    accel = np.stack([d["accel_x_mps2"], d["accel_y_mps2"], d["accel_z_mps2"]], 1)
    gyro = np.stack([d["gyro_p_rps"], d["gyro_q_rps"], d["gyro_r_rps"]], 1)
    v = np.stack([d["egi_v_north_mps"], d["egi_v_east_mps"], d["egi_v_down_mps"]], 1)
    bn = body_from_ned(d["egi_roll_rad"], d["egi_pitch_rad"], d["egi_heading_rad"])
    a_ned = (v[1:] - v[:-1]) / DT - np.array([0.0, 0.0, G])
    if len(a_ned) <= 40:
        return (0.0,) * 10
    gyro_means = [
        np.nanmax(np.abs(running_mean(gyro_residual(d, bn, subs), GYRO_TAU_S)), axis=0)
        for subs in (True, False)
    ]
    residual = accel[1:] - np.einsum("nij,nj->ni", 0.5 * (bn[1:] + bn[:-1]), a_ned)
    band = TIMING_S * (np.abs(np.cross(gyro[1:], accel[1:])) + np.abs(accel[1:] - accel[:-1]) / DT)
    banded = np.sign(residual) * np.maximum(np.abs(residual) - band, 0.0)
    worst = [np.nanmax(np.abs(running_mean(r)[40:]), axis=0) for r in (banded, residual)]
    return worst[0][1], worst[0][2], worst[1][1], worst[1][2], *gyro_means[0], *gyro_means[1]


def gyro_residual(d, bn, subs):
    """Per step, each gyro's rate over the step, less the body rate from the step's EGI attitude
    change (the skew part of C_k C_(k-1)^T, sin θ along the axis, taken to θ to second order). The
    gyro's: with `subs` the mean over the newer half of the previous frame period and the older
    half of this one, else the 20 Hz gyros weighted GYRO_20HZ_SHARE to this frame's."""
    if subs:
        sub = np.stack([np.stack([d[f"gyro_{a}_rps_sub{k}"] for a in "pqr"], 1) for k in range(6)], 1)
        gyro = 0.5 * (sub[:-1, 3:].mean(1) + sub[1:, :3].mean(1))
    else:
        g = np.stack([d[f"gyro_{a}_rps"] for a in "pqr"], 1)
        gyro = GYRO_20HZ_SHARE * g[1:] + (1.0 - GYRO_20HZ_SHARE) * g[:-1]
    m = np.einsum("nij,nkj->nik", bn[1:], bn[:-1])
    s = 0.5 * np.stack([m[:, 1, 2] - m[:, 2, 1], m[:, 2, 0] - m[:, 0, 2], m[:, 0, 1] - m[:, 1, 0]], 1)
    return gyro - s * (1.0 + (s * s).sum(1, keepdims=True) / 6.0) / DT


def running_mean(x, tau_s=TAU_S, block=200):
    """The filter's running mean (time constant tau_s, one step DT) of each column of x; a
    non-finite value is not folded in (the mean stands). Computed block by block in closed form,
    y[j] = a^(j+1) (y0 + k Σ_{i≤j} a^-(i+1) x[i]) with a = 1 - k, where the values are finite."""
    k = DT / (tau_s + DT)
    a = 1.0 - k
    out = np.empty_like(x)
    y0 = np.zeros(x.shape[1])
    for start in range(0, len(x), block):
        seg = x[start : start + block]
        if np.isfinite(seg).all():
            p = a ** np.arange(1, len(seg) + 1)[:, None]
            out[start : start + len(seg)] = p * (y0 + k * np.cumsum(seg / p, axis=0))
        else:
            mean = y0.copy()
            for i, r in enumerate(seg):
                ok = np.isfinite(r)
                mean[ok] += k * (r[ok] - mean[ok])
                out[start + i] = mean
        y0 = out[start + len(seg) - 1]
    return out


def main():
    args = sys.argv[1:]
    if len(args) != 1 or not os.path.isfile(os.path.join(args[0], "manifest.json")):
        sys.exit("usage: replay.py DATA_DIR (a hil-sim generate dataset)")
    # The manifest's flights (a flight-test dataset also holds each flight's boom record).
    with open(os.path.join(args[0], "manifest.json")) as f:
        files = sorted(fl["file"] for fl in json.load(f)["flights"])
    rows = [(name[:-4], *largest(os.path.join(args[0], name))) for name in files]
    worst = [max(rows, key=lambda r: r[c]) for c in range(1, 11)]
    print(
        f"{len(rows)} flights; largest running mean y {worst[0][1]:.2f} m/s² ({worst[0][0]}), "
        f"z {worst[1][2]:.2f} m/s² ({worst[1][0]}); without the dead band y {worst[2][3]:.2f} "
        f"({worst[2][0]}), z {worst[3][4]:.2f} ({worst[3][0]})"
    )
    print(
        "gyro check, largest running mean: "
        + ", ".join(
            f"{a} {w[c]:.4f} rad/s ({w[0]}) [{w20[c + 3]:.4f} ({w20[0]})]"
            for a, c, w, w20 in zip("pqr", (5, 6, 7), worst[4:7], worst[7:10])
        )
    )


if __name__ == "__main__":
    main()
