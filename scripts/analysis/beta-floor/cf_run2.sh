#!/bin/sh
# Counterfactual: every other test flight (gentle, high-α, climb) re-flown with its turbulence
# severity set to each value in 0..its own, sensor seed as in `generate`; answered by the shipped
# hybrid. At the flight's own severity the CSV must be byte-identical to $DATA's (cmp).
# Output: $WORK/cf/<flight>-sev<k>/; prints β and α MAE per variant.
set -e
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/env.sh"
mkdir -p "$WORK"
cd "$WORK"
SRC=$DATA
for spec in test_gentle_00:1500 test_high-alpha_01:1501 test_climb-descent_02:1502; do
  n=${spec%%:*}; seed=${spec##*:}
  S=$("$PY" -c "print($seed ^ 0x5e455e455e455e45)")
  own=$(grep -o 'milspec/severity" value="[0-9]*' $SRC/$n.xml | grep -o '[0-9]*$')
  for sev in $(seq 0 $own); do
    v=$n-sev$sev
    mkdir -p cf/script-$v
    sed "s|milspec/severity\" value=\"$own\"|milspec/severity\" value=\"$sev\"|" $SRC/$n.xml > cf/script-$v/$n.xml
    cp $SRC/${n}_init.xml cf/script-$v/
    nice -n 19 "$HIL_SIM" fly --script cf/script-$v/$n.xml --seed $S --out cf/$v --force > cf/$v.fly.log 2>&1
    if [ $sev = $own ]; then cmp cf/$v/$n.csv $SRC/$n.csv; fi
    nice -n 19 "$HIL_SIM" run --dataset cf/$v/$n.csv --firmware host --json --out cf/$v/run > cf/$v/run.json 2> cf/$v/run.err
    "$PY" -c "import json;j=json.load(open('cf/$v/run.json'));print('$v', 'beta', round(j['beta_mae_deg'],3), 'alpha', round(j['alpha_mae_deg'],3), 'frames', j['frames_scored'])"
  done
done
