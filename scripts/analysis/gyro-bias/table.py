"""The table of scripts/analysis/gyro-bias/run.sh: per gyro and bias size, over every onset of
every flight, the largest unflagged departure of the estimate from the fault-free run and how many
onsets pass the silent-error sizes. Usage: table.py NAME WORK COMMAND (prints Markdown)."""

import datetime
import glob
import json
import os
import platform
import sys

SILENT_DEG = (2.0, 1.0)  # α, β: the sizes a flight-control computer acts on


def main():
    name, work, command = sys.argv[1:4]
    rows = {}
    for path in sorted(glob.glob(os.path.join(work, "*", "*", "*", "summary.json"))):
        if os.path.dirname(path).endswith(".tmp"):
            continue  # a run cut short: run.sh flies it again
        gyro, size = os.path.basename(os.path.dirname(path)).split("-", 1)
        with open(path) as f:
            faults = json.load(f)["faults"]
        cell = rows.setdefault((gyro, float(size)), {"onsets": 0, "a": 0.0, "b": 0.0, "silent": 0,
                                                     "back": 0.0, "flights": set()})
        cell["flights"].add(os.path.dirname(os.path.dirname(path)))
        for fault in faults:
            a, b = fault["max_unflagged_dev_deg"]
            cell["onsets"] += 1
            cell["a"], cell["b"] = max(cell["a"], a), max(cell["b"], b)
            cell["silent"] += a > SILENT_DEG[0] or b > SILENT_DEG[1]
            back = fault["back_after_s"]
            cell["back"] = max(cell["back"], float("inf") if back is None else back)
    if not rows:
        sys.exit(f"gyro-bias: no summary.json under {work}: nothing was flown")
    flights = max(len(c["flights"]) for c in rows.values())
    print(f"# A gyro's bias shift: {name}\n")
    print(f"Command: `{command}`  ")
    print(f"Machine: {platform.machine()}, {os.cpu_count()} cores, "
          f"{datetime.date.today().isoformat()}\n")
    print(f"The {flights} test flights of the `paper` preset with seeds 11 and 12, each flown once per "
          "gyro and bias size with the bias on for 10 s every 25 s, 15 s of flight after each. *Unflagged departure*: the "
          "largest α / β difference from the fault-free run over the estimates that carry no flag, "
          "from the bias's onset to the next one; *past the silent sizes*: onsets whose unflagged "
          "departure exceeds 2° α or 1° β; *back*: the longest time from the bias's end to the "
          "estimate being back for 1 s: within 0.1° of the fault-free run, or between it and the truth "
          "widened by 0.1° (`hil_sim::score::faults`, dropout.md; inf: not back before the next onset).\n")
    print("| gyro | bias, rad/s | onsets | unflagged departure α / β, ° | past the silent sizes | back, s |")
    print("|---|---|---|---|---|---|")
    for (gyro, size), c in sorted(rows.items()):
        print(f"| {gyro} | {size:g} | {c['onsets']} | {c['a']:.3f} / {c['b']:.3f} | {c['silent']} | "
              f"{c['back']:.2f} |")


if __name__ == "__main__":
    main()
