#!/usr/bin/env python3
"""Instructions per MAC of each dense kernel of a flight image, counted on QEMU.

Flies the test flight on the image under qemu-system-arm (through `hil-sim run --firmware qemu`) with
the TCG plugin icount.c loaded, which counts the instructions executed inside every kernel function
(`accumulate_wide` / `accumulate_dsp`, one per layer shape, `#[inline(never)]`). The layer shapes come
from the weights file the image was built with, in the order `Estimator::step` runs them (α part 1,
α part 2, β part 1, β part 2). Prints a Markdown table.

    estimator-core/benches/qemu/kernel_icount.py ELF WEIGHTS_RS [--seconds 3] [--hil-sim PATH]

Needs gcc, llvm-nm, qemu-system-arm 7.2 and a built hil-sim (default target/release/hil-sim) with its
JSBSim venv. Kernel instruction counts do not depend on the data, so a few seconds of flight suffice.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def shapes(weights_rs):
    """(IN, OUT) of every layer, in execution order, from the generated statics' types."""
    text = Path(weights_rs).read_text()
    out = []
    for name in ("ALPHA", "BETA"):
        m = re.search(r"pub static %s: crate::CascadeNet<\n(.*)\n(.*)\n" % name, text)
        if not m:
            sys.exit(f"no {name} in {weights_rs}")
        for part in (m.group(1), m.group(2)):
            out += [(int(a), int(b)) for a, b in re.findall(r"(?:Hidden|Output)<(\d+), (\d+)>", part)]
    return out


def ranges(elf):
    """Estimator::step first (the report trigger), then every kernel function."""
    nm = subprocess.run(["llvm-nm", "-S", "-C", "--defined-only", elf], check=True, capture_output=True,
                        text=True).stdout
    step, kernels = [], []
    for line in nm.splitlines():
        p = line.split(None, 3)
        if len(p) < 4 or p[2] not in "tT":
            continue
        lo, size, name = int(p[0], 16), int(p[1], 16), p[3]
        if "Estimator::step" in name:
            step.append(("step", lo, lo + size))
        elif re.search(r"kernel::.*accumulate_(wide|dsp)", name):
            kernels.append((f"kernel@{lo:x}", lo, lo + size))
    if len(step) != 1 or not kernels:
        sys.exit(f"{elf}: expected Estimator::step and kernel functions in the symbol table")
    return step + kernels


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("elf")
    ap.add_argument("weights_rs")
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--hil-sim", default=str(ROOT / "target/release/hil-sim"))
    a = ap.parse_args()

    layers = shapes(a.weights_rs)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        plugin = tmp / "libicount.so"
        subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-fvisibility=hidden", "-o", str(plugin),
                        str(Path(__file__).with_name("icount.c"))], check=True)
        qemu = tmp / "qemu"
        qemu.write_text(f'#!/bin/sh\nexec qemu-system-arm -plugin {plugin} "$@"\n')
        qemu.chmod(0o755)
        cfg = tmp / "ranges"
        cfg.write_text("".join(f"{n} {lo:x} {hi:x}\n" for n, lo, hi in ranges(a.elf)))
        report = tmp / "report"
        env = dict(os.environ, ICOUNT_CFG=str(cfg), ICOUNT_OUT=str(report))
        run = subprocess.run([a.hil_sim, "run", "--script", str(ROOT / "flights/f16_test_flight.xml"),
                              "--firmware", "qemu", "--qemu", str(qemu), "--elf", a.elf, "--fast", "--json",
                              "--max-time-s", str(a.seconds), "--out", str(tmp / "run")],
                             env=env, check=True, capture_output=True, text=True)
        summary = json.loads(run.stdout)
        lines = report.read_text().splitlines()

    counts = {}
    for line in lines:
        p = line.split()
        if p[0] == "range" and int(p[3]) > 0:
            counts[p[1]] = int(p[2]) / int(p[3])
    entered = [line.split()[1] for line in lines if line.startswith("enter kernel@")]
    # The second step's calls (every step runs the same kernels in the same order).
    order = entered[len(layers):2 * len(layers)]
    if len(order) != len(layers):
        sys.exit("too few steps recorded: fly longer (--seconds)")

    print("| layer | MACs | instructions | instructions/MAC |")
    print("|---|---|---|---|")
    total = [0.0, 0]
    wide = [0.0, 0]
    for (n_in, n_out), name in zip(layers, order):
        ins, macs = counts[name], n_in * n_out
        total[0] += ins
        total[1] += macs
        if n_in >= 64:
            wide[0] += ins
            wide[1] += macs
        print(f"| {n_in}→{n_out} | {macs} | {ins:.0f} | {ins / macs:.3f} |")
    print(f"| all kernels | {total[1]} | {total[0]:.0f} | {total[0] / total[1]:.3f} |")
    if wide[1]:
        print(f"| layers with ≥ 64 inputs | {wide[1]} | {wide[0]:.0f} | {wide[0] / wide[1]:.3f} |")
    print(f"\nwhole step (median over {summary['frames_answered']} frames): "
          f"{summary['step_instructions_median']} instructions")


if __name__ == "__main__":
    main()
