"""Copies a flight-test dataset with its EGI channels (attitude and ground velocity) replaced by the
simulator's truth: a diagnostic of scripts/analysis/lift-offset-egi/run.sh, never a calibration
input (a flight-test aircraft records its EGI, not the truth).

    truth_egi.py SRC DST

Every other file of SRC (manifest, boom and engine logs) is linked into DST unchanged.
"""

import math
import os
import sys

# EGI channel <- truth column, and how the truth's degrees become the EGI's radians.
REPLACE = {
    "egi_roll_rad": ("phi_deg", math.radians),
    "egi_pitch_rad": ("theta_deg", math.radians),
    "egi_heading_rad": ("psi_deg", lambda d: math.radians(d) % (2 * math.pi)),
    "egi_v_north_mps": ("v_north_mps", float),
    "egi_v_east_mps": ("v_east_mps", float),
    "egi_v_down_mps": ("v_down_mps", float),
}


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: truth_egi.py SRC DST")
    src, dst = sys.argv[1:]
    os.makedirs(dst, exist_ok=True)
    flights = 0
    for name in sorted(os.listdir(src)):
        s, d = os.path.join(src, name), os.path.join(dst, name)
        if os.path.lexists(d):
            os.remove(d)
        head = open(s).readline() if name.endswith(".csv") else ""
        if "egi_pitch_rad" not in head:  # the manifest, the boom's and engine's logs, plots
            os.symlink(os.path.abspath(s), d)
            continue
        cols = head.strip().split(",")
        pairs = [(cols.index(e), cols.index(t), f) for e, (t, f) in REPLACE.items()]
        with open(s) as fi, open(d, "w") as fo:
            fo.write(fi.readline())
            for line in fi:
                c = line.rstrip("\n").split(",")
                for e, t, f in pairs:
                    c[e] = repr(f(float(c[t])))
                fo.write(",".join(c) + "\n")
        flights += 1
    if flights == 0:
        sys.exit(f"truth_egi.py: no flight with EGI channels in {src}")


if __name__ == "__main__":
    main()
