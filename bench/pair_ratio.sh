#!/usr/bin/env bash
# A photo pair's capture against a one-photo capture of its front-lit photo: RUNS rounds, each
# running `woven capture R --scene SCENE` then `woven capture R --transmission T --scene SCENE`
# (the default drape), timed whole (wall and CPU = user + system seconds of the process). In
# turn, so that a drift of the machine's speed falls on both. Prints JSON: each round's
# seconds and pair / one-photo ratio, their medians, the load average before and after.
# Usage: bench/pair_ratio.sh WOVEN R.png T.png [RUNS=3] [SCENE=flat45]
set -euo pipefail
WOVEN=$1 R=$2 TP=$3 RUNS=${4:-3} SCENE=${5:-flat45}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
load() { cut -d' ' -f1 /proc/loadavg; }
load_before=$(load)
for i in $(seq "$RUNS"); do
  /usr/bin/time -f "%e %U %S" -o "$T/one.$i" "$WOVEN" capture "$R" --scene "$SCENE" -o "$T/one" --force --quiet \
    2>"$T/err" || { cat "$T/err" >&2; exit 1; }
  /usr/bin/time -f "%e %U %S" -o "$T/pair.$i" "$WOVEN" capture "$R" --transmission "$TP" --scene "$SCENE" \
    -o "$T/pair" --force --quiet 2>"$T/err" || { cat "$T/err" >&2; exit 1; }
done
load_after=$(load)
python3 - "$T" "$RUNS" "$R" "$TP" "$SCENE" "$load_before" "$load_after" <<'PY'
import json, statistics, sys
t, runs, r, tp, scene, lb, la = sys.argv[1], int(sys.argv[2]), *sys.argv[3:]
def secs(f):
    wall, user, sys_ = (float(x) for x in open(f).read().split()[-3:])
    return wall, round(user + sys_, 2)
rounds = []
for i in range(1, runs + 1):
    ow, oc = secs(f"{t}/one.{i}")
    pw, pc = secs(f"{t}/pair.{i}")
    rounds.append({"one_wall_s": ow, "one_cpu_s": oc, "pair_wall_s": pw, "pair_cpu_s": pc,
                   "ratio_wall": round(pw / ow, 4), "ratio_cpu": round(pc / oc, 4)})
med = lambda k: statistics.median(x[k] for x in rounds)
print(json.dumps({"photo": r, "transmission": tp, "scene": scene, "runs": runs,
                  "load_before": float(lb), "load_after": float(la),
                  "one_wall_s_median": med("one_wall_s"), "pair_wall_s_median": med("pair_wall_s"),
                  "ratio_wall_median": med("ratio_wall"), "ratio_cpu_median": med("ratio_cpu"),
                  "rounds": rounds}, indent=1))
PY
