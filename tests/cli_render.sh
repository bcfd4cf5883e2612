#!/usr/bin/env bash
# CLI behaviour of `woven render` and `woven maps`: results, bad input, exit codes,
# no partial output, earlier results kept. Usage: cli_render.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"
small='{"name":"small","image":{"width":40,"height":20,"spp":4},"camera":{"position_mm":[0,0,250],"look_at_mm":[0,0,0],"vfov_deg":3},"sample":{"shape":"cylinder","radius_mm":35},"light":{"position_mm":[0,60,250],"intensity":150000}}'
echo "$small" >"$T/small.json"

# success: PNG and EXR, JSON summary
check "render png" 0 '"output"' -- "$WOVEN" render --params "$SRC/examples/twill.json" --scene "$T/small.json" -o "$T/a.png" --json
check "render exr" 0 "" -- "$WOVEN" render --params "$SRC/examples/satin.json" --scene "$T/small.json" -o "$T/a.exr" -q
"$WOVEN" render --params "$SRC/examples/twill.json" --scene "$T/small.json" -o "$T/b.png" --json >"$T/summary.json"
python3 -m json.tool "$T/summary.json" >/dev/null || { echo "FAIL --json is not JSON"; fails=$((fails + 1)); }
cmp -s "$T/a.png" "$T/b.png" || { echo "FAIL same inputs gave different PNGs"; fails=$((fails + 1)); }
"$WOVEN" render --params "$SRC/examples/twill.json" --scene "$T/small.json" -o "$T/c.png" --seed 9 -q
cmp -s "$T/a.png" "$T/c.png" && { echo "FAIL --seed did not change the noise"; fails=$((fails + 1)); }
check "help" 0 "usage: woven render" -- "$WOVEN" render --help
check "maps" 0 "tile_mm" -- "$WOVEN" maps --params "$SRC/examples/basket.json" -o "$T/maps" --size 32 --format both --json
for m in normal tangent yarn_id height diffuse specular roughness; do
  [[ -s $T/maps/$m.png && -s $T/maps/$m.exr ]] || { echo "FAIL maps: $m missing"; fails=$((fails + 1)); }
done
python3 -m json.tool "$T/maps/maps.json" >/dev/null || { echo "FAIL maps.json"; fails=$((fails + 1)); }

# bad input: clear message naming the file and field, meaningful exit code
printf '{"pattern": "twill",\n "density": {"warp": 120,, }}' >"$T/malformed.json"
check "malformed json" 4 "malformed.json:2:" -- "$WOVEN" render --params "$T/malformed.json" -o "$T/x.png"
echo '{"pattern": "houndstooth"}' >"$T/pattern.json"
check "unknown pattern" 2 "houndstooth" -- "$WOVEN" render --params "$T/pattern.json" -o "$T/x.png"
echo '{"pattern": "twill", "glossiness": 3}' >"$T/field.json"
check "unknown field" 2 "'glossiness'" -- "$WOVEN" render --params "$T/field.json" -o "$T/x.png"
echo '{"pattern": "twill", "roughness": {"warp": 7}}' >"$T/range.json"
check "out of range" 2 "roughness.warp" -- "$WOVEN" render --params "$T/range.json" -o "$T/x.png"
echo '{"pattern": "twill", "twist_deg": NaN}' >"$T/nan.json"
check "NaN" 4 "nan.json:1:" -- "$WOVEN" render --params "$T/nan.json" -o "$T/x.png"
echo "${small/\"spp\":4/\"spp\":4096}" | sed 's/"width":40,"height":20/"width":16000,"height":16000/' >"$T/huge.json"
check "too many samples" 5 "too many samples" -- "$WOVEN" render --params "$SRC/examples/twill.json" --scene "$T/huge.json" -o "$T/x.png"
check "spp option" 1 "--spp" -- "$WOVEN" render --params "$SRC/examples/twill.json" --spp 999999 -o "$T/x.png"
check "missing params" 3 "$T/none.json" -- "$WOVEN" render --params "$T/none.json" -o "$T/x.png"
check "unwritable dir" 3 "$T/no/dir/x.png" -- "$WOVEN" render --params "$SRC/examples/twill.json" --scene "$T/small.json" -o "$T/no/dir/x.png"
check "bad extension" 1 ".png or .exr" -- "$WOVEN" render --params "$SRC/examples/twill.json" -o "$T/x.jpg"
check "unknown option" 1 "--colour" -- "$WOVEN" render --colour
check "unknown command" 1 "unknown command" -- "$WOVEN" paint
echo "${small/cylinder/torus}" >"$T/torus.json" # a file: pipes are not read (docs/hardening.md)
check "bad scene" 2 "sample.shape" -- "$WOVEN" render --params "$SRC/examples/twill.json" --scene "$T/torus.json" -o "$T/x.png"
check "maps size" 1 "--size" -- "$WOVEN" maps --params "$SRC/examples/twill.json" -o "$T/m2" --size 0
[[ -e $T/x.png || -e $T/x.jpg || -e $T/m2 ]] && { echo "FAIL a failed command left an output"; fails=$((fails + 1)); }

# an earlier result survives a failed run, and no temporary files are left
cp "$T/a.png" "$T/keep.png"
"$WOVEN" render --params "$T/range.json" --scene "$T/small.json" -o "$T/keep.png" 2>/dev/null
cmp -s "$T/a.png" "$T/keep.png" || { echo "FAIL earlier output was changed by a failed run"; fails=$((fails + 1)); }
ls "$T" | grep -q '\.tmp\.' && { echo "FAIL temporary file left behind"; fails=$((fails + 1)); }

echo "$fails failure(s)"
[[ $fails == 0 ]]
