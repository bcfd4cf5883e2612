#!/usr/bin/env bash
# CLI behaviour of `woven scene` and `woven cloth`: results, JSON summaries,
# determinism, bad input (named in the message, meaningful exit code, nothing
# written), earlier results kept. Usage: cli_scene.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"

# a tiny draped cloth, made here (0.3 s of simulation), and a scene around it
check "cloth" 0 '"triangles": 128' -- "$WOVEN" cloth -o "$T/drape.obj" --res 8 --seconds 0.3 --json
"$WOVEN" cloth -o "$T/drape2.obj" --res 8 --seconds 0.3 -q
cmp -s "$T/drape.obj" "$T/drape2.obj" || { echo "FAIL cloth: same options gave different meshes"; fails=$((fails + 1)); }
scene() { # scene MESH ENV_JSON EXTRA_JSON
  cat <<JSON
{"image": {"width": 24, "height": 18, "spp": 2},
 "camera": {"position_mm": [0, 300, 560], "look_at_mm": [0, 70, 0], "vfov_deg": 32},
 "environment": $2,
 "materials": {"cloth": {"fabric": "$SRC/examples/twill.json", "uv_mm": [300, 300]}, "grey": {"lambert": 0.4}},
 "objects": [{"mesh": "$1", "material": "cloth"},
             {"sphere": {"centre_mm": [0, 80, 0], "radius_mm": 78, "segments": 24}, "material": "grey"}]$3}
JSON
}
scene "$T/drape.obj" '{"builtin": "studio", "width": 64}' "" >"$T/ok.json"
check "scene png" 0 '"rays_per_s"' -- "$WOVEN" scene "$T/ok.json" -o "$T/a.png" --json --threads 2
python3 -m json.tool "$T/out" >/dev/null || { echo "FAIL --json is not JSON"; fails=$((fails + 1)); }
check "scene exr" 0 "" -- "$WOVEN" scene "$T/ok.json" -o "$T/a.exr" -q --spp 1
"$WOVEN" scene "$T/ok.json" -o "$T/b.png" -q --threads 1
cmp -s "$T/a.png" "$T/b.png" || { echo "FAIL the thread count changed the image"; fails=$((fails + 1)); }
"$WOVEN" scene "$T/ok.json" -o "$T/c.png" -q --params "$SRC/examples/satin.json"
cmp -s "$T/a.png" "$T/c.png" && { echo "FAIL --params did not change the fabric"; fails=$((fails + 1)); }
# the bundled curtain, tiny: lit through the cloth, and darker with --no-transmission
check "curtain" 0 '"mean"' -- "$WOVEN" scene "$SRC/scenes/curtain-window.json" -o "$T/cw.png" --size 32x24 --spp 4 --json
lit=$(sed -n 's/.*"mean": \([0-9.e-]*\).*/\1/p' "$T/out")
check "curtain opaque" 0 '"mean"' -- "$WOVEN" scene "$SRC/scenes/curtain-window.json" -o "$T/cwo.png" --size 32x24 --spp 4 --json --no-transmission
dark=$(sed -n 's/.*"mean": \([0-9.e-]*\).*/\1/p' "$T/out")
python3 -c "import sys; sys.exit(0 if float('$lit') > 1.5 * float('$dark') else 1)" ||
  { echo "FAIL --no-transmission: mean $dark, not well below the transmitting $lit"; fails=$((fails + 1)); }
sed 's/"seed": 1, "transmission": true/"seed": 1, "transmission": 1/' "$SRC/scenes/curtain-window.json" >"$T/cwbad.json"
check "transmission not a boolean" 2 "'render.transmission' must be true or false" -- "$WOVEN" scene "$T/cwbad.json" -o "$T/x.png"
check "help" 0 "usage: woven scene" -- "$WOVEN" scene --help
check "cloth help" 0 "usage: woven cloth" -- "$WOVEN" cloth --help

# bad input: each names the file and the problem, exits non-zero, writes nothing
scene "$T/none.obj" '{"builtin": "studio"}' "" >"$T/nomesh.json"
check "missing mesh" 3 "$T/none.obj" -- "$WOVEN" scene "$T/nomesh.json" -o "$T/x.png"
head -c 300 "$T/drape.obj" >"$T/cut.obj"
scene "$T/cut.obj" '{"builtin": "studio"}' "" >"$T/cut.json"
check "truncated mesh" 4 "$T/cut.obj" -- "$WOVEN" scene "$T/cut.json" -o "$T/x.png"
echo "solid nonsense" >"$T/junk.obj"
scene "$T/junk.obj" '{"builtin": "studio"}' "" >"$T/junk.json"
check "malformed mesh" 4 "$T/junk.obj" -- "$WOVEN" scene "$T/junk.json" -o "$T/x.png"
scene "$T/drape.obj" "{\"file\": \"$T/none.exr\"}" "" >"$T/noenv.json"
check "missing environment" 3 "$T/none.exr" -- "$WOVEN" scene "$T/noenv.json" -o "$T/x.png"
head -c 200 "$T/a.exr" >"$T/cut.exr"
scene "$T/drape.obj" "{\"file\": \"$T/cut.exr\"}" "" >"$T/cutenv.json"
check "truncated environment" 4 "$T/cut.exr" -- "$WOVEN" scene "$T/cutenv.json" -o "$T/x.png"
scene "$T/drape.obj" "{\"file\": \"$T/a.png\"}" "" >"$T/pngenv.json"
check "environment not EXR" 4 "must be an EXR" -- "$WOVEN" scene "$T/pngenv.json" -o "$T/x.png"
scene "$T/drape.obj" '{"builtin": "studio"}' \
  ", \"edits\": [{\"material\": \"cloth\", \"apply\": \"diffuse_multiply\", \"map\": \"$T/a.png\", \"mask\": \"$SRC/examples/edits/logo_mask.png\"}]" >"$T/size.json"
check "edit mask of another size" 4 "logo_mask.png: the mask is 256 x 256" -- "$WOVEN" scene "$T/size.json" -o "$T/x.png"
scene "$T/drape.obj" '{"builtin": "studio"}' \
  ", \"edits\": [{\"material\": \"cloth\", \"apply\": \"roughness\", \"map\": \"$SRC/examples/edits/logo.png\"}]" >"$T/type.json"
check "edit map of the wrong type" 4 "logo.png: must be a grey image" -- "$WOVEN" scene "$T/type.json" -o "$T/x.png"
sed "s#$SRC/examples/twill.json#$T/gone.json#" "$T/ok.json" >"$T/noparams.json"
check "missing parameter file" 3 "$T/gone.json" -- "$WOVEN" scene "$T/noparams.json" -o "$T/x.png"
"$WOVEN" cloth -o "$T/big.obj" --res 200 --seconds 0 -q
scene "$T/big.obj" '{"builtin": "studio"}' "" >"$T/big.json"
check "mesh over the memory limit" 5 "memory limit" -- "$WOVEN" scene "$T/big.json" -o "$T/x.png" --mesh-limit-mb 2
echo "{\"image\": " >"$T/broken.json"
check "malformed scene" 4 "broken.json:2:" -- "$WOVEN" scene "$T/broken.json" -o "$T/x.png"
echo '{"image": {"width": 8, "height": 8}, "camera": {"position_mm": [0,0,1], "look_at_mm": [0,0,0], "vfov_deg": 30}, "materials": {"m": {"lambert": 0.5}}, "objects": [{"torus": {}, "material": "m"}]}' >"$T/bad.json"
check "unknown object" 2 "objects[0].torus" -- "$WOVEN" scene "$T/bad.json" -o "$T/x.png"
check "missing scene" 3 "$T/none.json" -- "$WOVEN" scene "$T/none.json" -o "$T/x.png"
check "bad extension" 1 ".png or .exr" -- "$WOVEN" scene "$T/ok.json" -o "$T/x.jpg"
check "unknown option" 1 "--colour" -- "$WOVEN" scene "$T/ok.json" --colour
check "cloth bad obstacle" 1 "--obstacle" -- "$WOVEN" cloth -o "$T/y.obj" --obstacle cone
[[ -e $T/x.png || -e $T/y.obj ]] && { echo "FAIL a failed command left an output"; fails=$((fails + 1)); }

# an earlier result survives a failed run, and no temporary files are left
cp "$T/a.png" "$T/keep.png"
"$WOVEN" scene "$T/nomesh.json" -o "$T/keep.png" 2>/dev/null
cmp -s "$T/a.png" "$T/keep.png" || { echo "FAIL earlier output was changed by a failed run"; fails=$((fails + 1)); }
ls "$T" | grep -q '\.tmp\.' && { echo "FAIL temporary file left behind"; fails=$((fails + 1)); }

echo "$fails failure(s)"
[[ $fails == 0 ]]
