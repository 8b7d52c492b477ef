#!/bin/sh
# Counterfactual re-flights of test_aggressive_03 (same maneuver script, same sensor seed as
# `generate` used: flight seed 1503 ^ 0x5e455e455e455e45), each answered by the shipped hybrid.
# Plant variants: Milspec severity 0, 2..6; sensor variants (--sensors TOML): no IMU anti-alias,
# 12 Hz anti-alias, EGI fresh (latency 0, 120 Hz), EGI fresh and error-free.
# Output: $WORK/cf/<variant>/; prints β and α MAE per variant.
set -e
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/env.sh"
mkdir -p "$WORK"
cd "$WORK"
S=$("$PY" -c "print(1503 ^ 0x5e455e455e455e45)")
SRC=$DATA
fly() {  # name script [sensors]
  if [ -n "$3" ]; then extra="--sensors $3"; else extra=""; fi
  nice -n 19 "$HIL_SIM" fly --script "$2" --seed $S --out cf/$1 --force $extra > cf/$1.fly.log 2>&1
  nice -n 19 "$HIL_SIM" run --dataset cf/$1/$(basename "$2" .xml).csv --firmware host --json --out cf/$1/run > cf/$1/run.json 2> cf/$1/run.err
  "$PY" -c "import json;j=json.load(open('cf/$1/run.json'));print('$1', 'beta', round(j['beta_mae_deg'],3), 'alpha', round(j['alpha_mae_deg'],3), 'scored', j['frames_scored'])"
}
for sev in 0 2 3 4 5 6; do
  mkdir -p cf/script-sev$sev
  sed "s|milspec/severity\" value=\"6\"|milspec/severity\" value=\"$sev\"|" $SRC/test_aggressive_03.xml > cf/script-sev$sev/test_aggressive_03.xml
  cp $SRC/test_aggressive_03_init.xml cf/script-sev$sev/
  grep -c "severity\" value=\"$sev\"" cf/script-sev$sev/test_aggressive_03.xml > /dev/null
  fly sev$sev cf/script-sev$sev/test_aggressive_03.xml
done
cat > cf/no-aa.toml <<'T'
[imu]
antialias_cutoff_hz = 0.0
lag_tau_s = 0.0
T
cat > cf/aa-12hz.toml <<'T'
[imu]
antialias_cutoff_hz = 12.0
T
cat > cf/egi-fresh.toml <<'T'
[egi]
latency_s = 0.0
attitude_hz = 120.0
heading_hz = 120.0
velocity_hz = 120.0
T
cat > cf/egi-exact.toml <<'T'
[egi]
latency_s = 0.0
attitude_hz = 120.0
heading_hz = 120.0
velocity_hz = 120.0
attitude_gm_sigma_deg = 0.0
attitude_noise_sigma_deg = 0.0
heading_gm_sigma_deg = 0.0
heading_noise_sigma_deg = 0.0
velocity_gm_sigma_mps = 0.0
velocity_noise_sigma_mps = 0.0
T
for v in no-aa aa-12hz egi-fresh egi-exact; do
  fly sens-$v $SRC/test_aggressive_03.xml cf/$v.toml
done
