#!/usr/bin/env bash
# `woven capture` on photos without a weave (a flat grey card, sand-like noise) with the
# default flat45 model: no crash; the weave analysis says it found no lattice, the
# pattern comes from the network's pattern head, and fit.json and report.html say so.
# Usage: cli_nolattice.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"
fail() { echo "FAIL $*"; fails=$((fails + 1)); }
python3 - "$T" "$(dirname "$0")" <<'PY' || fail "could not write the test photos"
import random, sys
sys.dont_write_bytecode = True  # nothing written into the source tree
sys.path.insert(0, sys.argv[2])
from png_write import png
png(sys.argv[1] + '/grey.png', 512, 512, [128] * (512 * 512 * 3))
r = random.Random(5)  # seeded: the same sand every run
png(sys.argv[1] + '/sand.png', 512, 512, [min(255, max(0, int(r.gauss(140, 30)))) for _ in range(512 * 512 * 3)])
PY
for im in grey sand; do
  check "capture of $im" 0 '"method": "network"' -- "$WOVEN" capture "$T/$im.png" --scene flat45 -o "$T/c_$im" \
    --iters 2 --align-radius 0 --register-radius 0 --json
  grep -q '"found": false' "$T/c_$im/fit.json" || fail "$im: fit.json does not record that no lattice was found"
  grep -q '"method": "network"' "$T/c_$im/fit.json" || fail "$im: fit.json does not record the network's choice"
  grep -q "found no weave lattice" "$T/c_$im/report.html" || fail "$im: the report does not say no lattice was found"
  [[ -s $T/c_$im/params.json && -s $T/c_$im/render.png ]] || fail "$im: the capture's results are missing"
done
echo "$fails failure(s)"
[[ $fails == 0 ]]
