#!/usr/bin/env bash
# woven capture's time: RUNS captures of one photo (default: the flat45 scene, no --pattern,
# as the demo and bench/recover run it), each timed whole (wall and CPU = user + system
# seconds of the process) with the fit's own breakdown (--json time_s: render, gradient,
# descriptor, discrete steps, registration, distortion) and the pattern choice's seconds.
# Prints JSON: the medians, every run, the load average before and after (the machine may
# be shared: CPU seconds depend little on the load, wall seconds do), and the last run's
# quality (SSIM per RGB channel, WSC, family, iterations; with --transmission the back-lit
# photo's SSIM, its blurred copy's, WSC, open area and mean brightness) so a faster run can be checked.
# Usage: bench/capture_speed.sh WOVEN PHOTO [RUNS=3] [CAPTURE ARGS... (default --scene flat45)]
set -euo pipefail
WOVEN=$1 PHOTO=$2 RUNS=${3:-3}
shift $(($# < 3 ? $# : 3))
ARGS=("$@")
[ ${#ARGS[@]} -gt 0 ] || ARGS=(--scene flat45)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
load() { cut -d' ' -f1 /proc/loadavg; }
load_before=$(load)
for i in $(seq "$RUNS"); do
  /usr/bin/time -f "%e %U %S" -o "$T/time.$i" "$WOVEN" capture "$PHOTO" "${ARGS[@]}" -o "$T/out" --force --json \
    >"$T/run.$i.json" 2>"$T/err.$i" || { cat "$T/err.$i" >&2; exit 1; }
done
load_after=$(load)
python3 - "$T" "$RUNS" "$PHOTO" "$load_before" "$load_after" "${ARGS[*]}" <<'EOF'
import json, statistics, sys
t, runs, photo, lb, la, args = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5], sys.argv[6]
rows = []
for i in range(1, runs + 1):
    wall, user, sys_ = (float(x) for x in open(f"{t}/time.{i}").read().split()[-3:])
    d = json.load(open(f"{t}/run.{i}.json"))
    stages = dict(d["time_s"])
    stages["pattern_choice"] = (d.get("pattern_choice") or {}).get("seconds", 0.0)
    rows.append({"wall_s": wall, "cpu_s": round(user + sys_, 2), "stages_s": stages, "summary": d})
med = lambda k: statistics.median(r[k] for r in rows)
keys = rows[0]["stages_s"].keys()
last = rows[-1]["summary"]
out = {
    "photo": photo, "args": args, "runs": runs, "load_before": float(lb), "load_after": float(la),
    "wall_s_median": med("wall_s"), "cpu_s_median": med("cpu_s"),
    "stages_s_median": {k: round(statistics.median(r["stages_s"][k] for r in rows), 3) for k in keys},
    "quality": {"iterations": last.get("iterations"), "ssim_rgb_fit": last.get("ssim_rgb_fit"),
                "wsc_fit": last.get("wsc_fit"), "wsc_whitened_fit": last.get("wsc_whitened_fit"),
                "family": (last.get("pattern_choice") or {}).get("family"),
                "pattern": (last.get("pattern_choice") or {}).get("chosen"),
                **{k: last[k] for k in ("ssim_rgb_fit_t", "ssim_rgb_blurred_photo_t", "wsc_fit_t", "open_area_photo",
                                        "open_area_fit", "mean_t") if k in last}},
    "each": [{"wall_s": r["wall_s"], "cpu_s": r["cpu_s"], "stages_s": r["stages_s"]} for r in rows],
}
print(json.dumps(out))
EOF
