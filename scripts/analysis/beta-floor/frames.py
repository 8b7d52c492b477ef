"""Per-frame table of one flight: dataset columns + the shipped estimator's answer + (when a 120 Hz
replay exists) JSBSim internals at the sample instants and 120 Hz series.

Helper (computes no figure itself): joins $DATA/<flight>.csv, $WORK/run-<flight>/estimates.csv and
$WORK/replay/<flight>.npz (replay120.py), checking they describe the same frames."""
import os

import numpy as np

from common import WORK, load_estimates, load_flight

ZONE_NAMES = {0: "flight", 1: "danger", 2: "reclimb"}


def load_replay(name):
    p = os.path.join(WORK, "replay", name + ".npz")
    if not os.path.exists(p):
        return None
    r = dict(np.load(p))
    return {k: v.astype(np.float64) for k, v in r.items()}


def table(name, with_replay=True):
    d = dict(load_flight(name))
    # The estimator's answers are optional (the floors do not read them): without
    # $WORK/run-<flight>/estimates.csv the estimate columns are NaN.
    if os.path.exists(os.path.join(WORK, "run-" + name, "estimates.csv")):
        e = load_estimates(name)
        assert len(e["seq"]) == len(d["time_s"]), name
        assert np.all(e["received"] == 1), name
        assert np.allclose(e["beta_true_deg"], d["beta_deg"], atol=2e-6)
        d["beta_hat"] = e["beta_deg"]
        d["alpha_hat"] = e["alpha_deg"]
        d["v_aero_hat"] = e["v_aero_mps"]
        d["est_flags"] = e["flags"]
    else:
        nan = np.full(len(d["time_s"]), np.nan)
        d["beta_hat"] = d["alpha_hat"] = d["v_aero_hat"] = nan
        d["est_flags"] = np.full(len(d["time_s"]), -1)
    d["err"] = d["beta_hat"] - d["beta_deg"]
    d["aerr"] = d["alpha_hat"] - d["alpha_deg"]
    n = len(d["time_s"])
    if with_replay:
        r = load_replay(name)
        if r is not None:
            idx = np.arange(5, len(r["simulation__sim_time_sec"]), 6)[:n]
            assert np.max(np.abs(r["simulation__sim_time_sec"][idx] - d["time_s"])) < 1e-3
            assert np.max(np.abs(np.degrees(r["aero__beta_rad"][idx]) - d["beta_deg"])) < 1e-4
            d["r120"] = r
            d["idx120"] = idx
            for k, v in r.items():
                d["rp_" + k] = v[idx]
    return d


def beta_dot_deg_s(d):
    """Truth β̇ at the samples, deg/s: central difference on the 120 Hz replay if there, else 20 Hz."""
    if "r120" in d:
        b = np.degrees(d["r120"]["aero__beta_rad"])
        bd = np.gradient(b, 1 / 120.0)
        return bd[d["idx120"]]
    return np.gradient(d["beta_deg"], 0.05)
