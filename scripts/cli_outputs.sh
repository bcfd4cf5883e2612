#!/usr/bin/env bash
# Runs a fixed set of woven commands and keeps every output, so that two builds can be
# compared file by file (a restructuring must leave every byte as it was):
#   scripts/cli_outputs.sh WOVEN_BINARY OUT_DIR [PHOTO_FLAT45]
#   diff -r OLD_OUT NEW_OUT
# Timings, the output's own path and the checkout's path are blanked in the JSON and HTML outputs, since
# they differ from run to run of the same build.
set -euo pipefail
wv=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
out=$2
photo=${3:-}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
cd "$root"
q=(--quiet --threads 2)
"$wv" render --params examples/twill.json --scene cylinder -o "$out/render_cyl.png" "${q[@]}"
"$wv" render --params examples/satin.json --scene flat45 -o "$out/render_flat.exr" --spp 8 "${q[@]}"
"$wv" render --params examples/twill.json --scene scenes/flat45.json -o "$out/render_flat.png" --json --threads 2 > "$out/render_flat.json"
"$wv" maps --params examples/twill.json --size 128 --format both -o "$out/maps" --quiet
"$wv" fit examples/photo_twill_cylinder.png --scene cylinder --pattern twill -o "$out/fit" --iters 12 --drape none "${q[@]}"
"$wv" capture examples/photo_twill_cylinder.png --scene cylinder --pattern twill -o "$out/capture" --iters 12 --drape none "${q[@]}" --json > "$out/capture.json"
"$wv" capture examples/photo_twill_cylinder.png --scene cylinder -o "$out/capture_auto" --iters 6 --drape none "${q[@]}"
"$wv" predict examples/photo_twill_cylinder.png --scene cylinder -o "$out/predict.json" --json --quiet > "$out/predict_summary.json"
"$wv" export "$out/capture" --gltf "$out/export.glb" --texture 16 --directions 16 "${q[@]}"
"$wv" scene scenes/drape-studio.json --params examples/twill.json -o "$out/scene.png" --size 160x120 --spp 4 "${q[@]}"
"$wv" scene scenes/drape-edits.json -o "$out/scene_edits.exr" --size 128x96 --spp 2 "${q[@]}"
"$wv" view "$out/capture" -o "$out/viewer.html" --quiet
"$wv" compare examples/photo_twill_cylinder.png "$out/capture/render.png" --json > "$out/compare.json"
"$wv" compare examples/photo_twill_cylinder.png "$out/capture/render.png" --channels rgb --blur 4 --json > "$out/compare_rgb.json"
if [[ -n $photo ]]; then
  "$wv" capture "$photo" --scene flat45 -o "$out/capture_flat" --iters 10 --drape none "${q[@]}"
fi
# Wall-clock figures and the output's own path differ between runs of one build: blank them.
find "$out" -name 'times.json' -delete
find "$out" -name '*.json' -print0 | OUT="$(cd "$out" && pwd)" ROOT="$root" xargs -0 python3 -c '
import json, os, sys
def blank(v):
    if isinstance(v, dict):
        return {k: (0 if k in ("timing", "time_s", "seconds", "ms") or k.endswith("_seconds") else blank(x))
                for k, x in v.items()}
    if isinstance(v, str):
        return v.replace(os.environ["OUT"], "OUT").replace(os.environ["ROOT"], "ROOT")
    return [blank(x) for x in v] if isinstance(v, list) else v
for path in sys.argv[1:]:
    with open(path) as f:
        try:
            doc = json.load(f)
        except ValueError:
            continue
    with open(path, "w") as f:
        json.dump(blank(doc), f, sort_keys=True)
'
find "$out" -name '*.html' -print0 | xargs -0 sed -i -E 's/Time: [^<]*/Time: -/g'
echo "outputs in $out"
