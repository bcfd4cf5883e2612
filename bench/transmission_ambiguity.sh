#!/usr/bin/env bash
# How far apart a back-lit photo tells the two transmission colours: the diffuse k_t and the
# specular k_st. A truth (examples/twill.json with yarn width 0.9, k_t 0.3 and k_st 0.5 grey on
# both yarn types) is rendered in flat45-back; so is the same cloth with another noise seed
# (what any re-render of the truth can reach), and cloths whose k_st is K times the truth's
# with k_t stepped over a grid, the closest (least mean absolute difference) kept. Prints
# JSON: SSIM per RGB channel, WSC and mean absolute difference of each against the truth.
# Usage: bench/transmission_ambiguity.sh WOVEN [K...] (default K: 0.5 2)
set -euo pipefail
usage() { echo "usage: bench/transmission_ambiguity.sh WOVEN [K...] (0 < K <= 2)" >&2; exit 2; }
[ $# -ge 1 ] && [ -x "$1" ] || usage
WOVEN=$1
shift
FACTORS=("$@")
[ ${#FACTORS[@]} -gt 0 ] || FACTORS=(0.5 2)
for k in "${FACTORS[@]}"; do # k_st = 0.5 K must stay within its range 0..1
  python3 -c "import sys; k = float(sys.argv[1]); sys.exit(0 if 0 < k <= 2 else 1)" "$k" 2>/dev/null ||
    { echo "transmission_ambiguity: K = '$k' is not a number in (0, 2]" >&2; exit 2; }
done
HERE=$(cd "$(dirname "$0")/.." && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
params() { # name k_t k_st seed
  python3 - "$HERE/examples/twill.json" "$T/$1.json" "$2" "$3" "$4" <<'EOF'
import json, sys
p = json.load(open(sys.argv[1]))
kt, kst, seed = float(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
p.update(yarn_width=0.9, seed=seed, transmission={"warp": [kt] * 3, "weft": [kt] * 3},
         transmission_specular={"warp": [kst] * 3, "weft": [kst] * 3})
json.dump(p, open(sys.argv[2], "w"))
EOF
  "$WOVEN" render --params "$T/$1.json" --scene flat45-back -o "$T/$1.png" --quiet
}
compare() { # the figures only, not the temporary paths
  "$WOVEN" compare "$T/truth.png" "$T/$1.png" --channels rgb --json |
    python3 -c "import json, sys; d = json.load(sys.stdin); print(json.dumps({k: d[k] for k in ('ssim', 'wsc', 'mae')}))"
}
params truth 0.3 0.5 1
params seed 0.3 0.5 7
{
  echo "{\"truth\": {\"k_t\": 0.3, \"k_st\": 0.5}, \"other_seed\": $(compare seed), \"scaled\": ["
  sep=""
  for k in "${FACTORS[@]}"; do
    kst=$(python3 -c "print(round(0.5 * $k, 4))")
    best="" best_mae=1e9
    for kt in 0.05 0.1 0.15 0.2 0.25 0.3 0.35 0.4 0.45 0.5 0.55 0.6; do
      params "k$k-$kt" "$kt" "$kst" 1
      c=$(compare "k$k-$kt")
      m=$(python3 -c "import json, sys; print(json.loads(sys.argv[1])['mae'])" "$c")
      if python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) < float(sys.argv[2]) else 1)" "$m" "$best_mae"; then
        best_mae=$m best="{\"factor\": $k, \"k_st\": $kst, \"k_t\": $kt, \"compare\": $c}"
      fi
    done
    echo "$sep$best"
    sep=","
  done
  echo "]}"
} | python3 -c "import json, sys; print(json.dumps(json.load(sys.stdin)))"
