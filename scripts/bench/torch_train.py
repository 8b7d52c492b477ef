"""The PyTorch side of `trainer bench-train` (started by it; see scripts/bench-train).

Reads the exchange directory the trainer wrote: the prepared design matrices (little-endian f32),
the initial weights of both cascade parts (burn's own initialisation, [out][in] rows then the bias),
the row order of every epoch and meta.json (sizes, batch, per-epoch learning rates, Adam
constants). Trains the same cascade on the same batches in the same order with the same optimiser
and the same per-epoch validation pass.

It runs in lockstep with burn so both see the same machine: it prints one JSON line with its
versions, then for each epoch number read from stdin trains that epoch and prints one JSON line
(seconds, mean training losses, validation losses). Nothing here decides a result: the trainer
compares the two runs.
"""

import argparse
import json
import os
import sys
import time

import numpy as np
import torch


def load(d, name, shape):
    a = np.fromfile(os.path.join(d, name), dtype="<f4")
    return torch.from_numpy(a.reshape(shape).copy())


def mlp(dims):
    layers = []
    for k in range(len(dims) - 1):
        layers.append(torch.nn.Linear(dims[k], dims[k + 1]))
        if k + 2 < len(dims):
            layers.append(torch.nn.ReLU())
    return torch.nn.Sequential(*layers)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("exchange")
    ap.add_argument("--threads", type=int, required=True)
    a = ap.parse_args()
    d = a.exchange
    torch.set_num_threads(a.threads)
    meta = json.load(open(os.path.join(d, "meta.json")))
    n_in, hidden = meta["n_in"], meta["hidden"]
    n_tr, n_va, batch = meta["train_rows"], meta["val_rows"], meta["batch"]
    epochs = len(meta["lr"])

    x_tr = load(d, "x_train.f32", (n_tr, n_in))
    ym_tr = load(d, "ym_train.f32", (n_tr, 1))
    yo_tr = load(d, "yo_train.f32", (n_tr, 1))
    x_va = load(d, "x_val.f32", (n_va, n_in))
    ym_va = load(d, "ym_val.f32", (n_va, 1))
    yo_va = load(d, "yo_val.f32", (n_va, 1))
    order = np.fromfile(os.path.join(d, "order.u32"), dtype="<u4").reshape(epochs, n_tr)
    order = torch.from_numpy(order.astype(np.int64))

    part1 = mlp([n_in] + hidden + [1])
    part2 = mlp([n_in + 1] + hidden + [1])
    init = np.fromfile(os.path.join(d, "init.f32"), dtype="<f4")
    off = 0
    with torch.no_grad():
        for lin in [m for p in (part1, part2) for m in p if isinstance(m, torch.nn.Linear)]:
            o, i = lin.weight.shape
            lin.weight.copy_(torch.from_numpy(init[off : off + o * i].reshape(o, i).copy()))
            off += o * i
            lin.bias.copy_(torch.from_numpy(init[off : off + o].copy()))
            off += o
    if off != init.size:
        raise SystemExit(f"init.f32 holds {init.size} values, the cascade takes {off}")

    params = list(part1.parameters()) + list(part2.parameters())
    # fused=True: PyTorch's fastest Adam on the CPU (7.0-7.2 s against 9-12 s per paper-size epoch
    # for the default and foreach variants here); the same update rule.
    opt = torch.optim.Adam(
        params,
        lr=meta["lr"][0],
        betas=(meta["beta_1"], meta["beta_2"]),
        eps=meta["epsilon"],
        fused=True,
    )
    # The training loss of both heads, as burn's (`trainer::model::Loss`); the validation pass
    # scores the same one.
    kind = meta.get("loss", "mse")
    if kind not in ("mse", "l1"):
        raise SystemExit(f"meta.json: loss {kind!r} is neither mse nor l1")
    l1 = kind == "l1"
    loss = torch.nn.functional.l1_loss if l1 else torch.nn.functional.mse_loss

    def err(p, y):
        d = (p - y).double()
        return float((d.abs() if l1 else d**2).sum())

    def forward(x):
        mid = part1(x)
        return mid, part2(torch.cat([x, mid], 1))

    def emit(obj):
        sys.stdout.write(json.dumps(obj) + "\n")
        sys.stdout.flush()

    emit({"torch": torch.__version__, "threads": torch.get_num_threads()})
    for line in sys.stdin:
        epoch = int(line)
        t0 = time.perf_counter()
        for g in opt.param_groups:
            g["lr"] = meta["lr"][epoch]
        perm = order[epoch]
        sm = so = 0.0
        nb = 0
        for s in range(0, n_tr, batch):
            idx = perm[s : s + batch]
            mid, o = forward(x_tr[idx])
            lm, lo = loss(mid, ym_tr[idx]), loss(o, yo_tr[idx])
            opt.zero_grad(set_to_none=True)
            (lm + lo).backward()
            opt.step()
            sm += lm.item()
            so += lo.item()
            nb += 1
        with torch.no_grad():
            em = eo = 0.0
            for s in range(0, n_va, 8192):
                mid, o = forward(x_va[s : s + 8192])
                em += err(mid, ym_va[s : s + 8192])
                eo += err(o, yo_va[s : s + 8192])
        dt = time.perf_counter() - t0
        val = [em / max(n_va, 1), eo / max(n_va, 1)]
        print(f"torch epoch {epoch + 1}/{epochs}: {dt:.2f} s, val {val[0]:.5f}/{val[1]:.5f}",
              file=sys.stderr, flush=True)
        emit({"epoch_s": dt, "train": [sm / nb, so / nb], "val": val})


if __name__ == "__main__":
    main()
