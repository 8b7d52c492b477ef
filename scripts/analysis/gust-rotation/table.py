"""The table of scripts/analysis/gust-rotation/run.sh: per aircraft, each test flight's α and β MAE
(int8, deployed) on the model, on the model whose aerodynamics do not feel the turbulence's
rotation, and on the one that feels it nowhere (aerodynamics and flight controls), and all four.

    table.py NAME=MODEL_EVAL_JSON,AERODYNAMICS_EVAL_JSON,EVERYWHERE_EVAL_JSON ...
"""

import json
import sys


def per_flight(path):
    e = json.load(open(path))
    rows = {a: {n: m for n, m in e[a]["per_flight"]} for a in ("alpha", "beta")}
    return e, rows


def main():
    print("α / β MAE, degrees: the model / its aerodynamics without the rotation / without it anywhere")
    print()
    print("| aircraft | flight | α | β |")
    print("|---|---|---|---|")
    for arg in sys.argv[1:]:
        name, paths = arg.split("=", 1)
        runs = [per_flight(p) for p in paths.split(",")]
        for flight in runs[0][1]["alpha"]:
            cells = [" / ".join(f"{r[a][flight]['mae']:.3f}" for _, r in runs) for a in ("alpha", "beta")]
            print(f"| {name} | {flight.removeprefix('test_')} | {cells[0]} | {cells[1]} |")
        cells = ["**" + " / ".join(f"{e[a]['overall']['mae']:.3f}" for e, _ in runs) + "**" for a in ("alpha", "beta")]
        print(f"| {name} | all four | {cells[0]} | {cells[1]} |")


if __name__ == "__main__":
    main()
