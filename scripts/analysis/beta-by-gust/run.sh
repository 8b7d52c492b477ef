#!/usr/bin/env bash
# β (and α) error against the turbulence each test flight flew, the F-16 beside the c172p
# (docs/results/c172p.md, "β and turbulence"): the `paper` preset's test flights with seeds 11-18,
# none of which trained either shipped estimator, each aircraft's shipped estimator on them
# (`trainer eval --json`, beside each dataset as DIR.eval.json), then table.py.
# Needs the release builds of both aircraft (the F-16's in target/, the c172p's in target/c172p:
# ESTIMATOR_AIRCRAFT=c172p CARGO_TARGET_DIR=target/c172p cargo build --release -p hil-sim -p trainer)
# and the project's .venv (scripts/bootstrap). Writes into out/turb/; about 2 min on 2 cores.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
cd "$root"
out=out/turb
mkdir -p "$out"
fly() {  # fly NAME SEED BIN_DIR [--aircraft NAME]
  local name="$1" seed="$2" bin="$3"; shift 3
  local d="$out/$name-$seed"
  [ -f "$d/manifest.json" ] || "$bin/hil-sim" generate "$@" --preset paper --test-only --seed "$seed" --out "$d" >&2
  [ -f "$d.eval.json" ] || "$bin/trainer" eval "$@" --data "$d" --json > "$d.eval.json"
  printf '%s' "$d"
}
f16=() c172p=()
for s in 11 12 13 14 15 16 17 18; do
  f16+=("$(fly f16 "$s" target/release)")
  c172p+=("$(fly c172p "$s" target/c172p/release --aircraft c172p)")
done
.venv/bin/python scripts/analysis/beta-by-gust/table.py \
  "f16=$(IFS=,; echo "${f16[*]}")" "c172p=$(IFS=,; echo "${c172p[*]}")"
