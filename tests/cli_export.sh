#!/usr/bin/env bash
# CLI behaviour of `woven export` and `woven view`: results, bad input, exit codes,
# nothing written on failure, an earlier result kept. Usage: cli_export.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"
ex="$SRC/examples/twill.json"
small=(--texture 8 --samples 1 --directions 8)

check "export help" 0 "usage: woven export" -- "$WOVEN" export --help
check "export quad" 0 '"relative"' -- "$WOVEN" export "$ex" --gltf "$T/a.glb" "${small[@]}" --json
python3 -m json.tool "$T/out" >/dev/null || { echo "FAIL export --json is not JSON"; fails=$((fails + 1)); }
head -c 4 "$T/a.glb" | grep -q glTF || { echo "FAIL a.glb is not a glTF binary"; fails=$((fails + 1)); }
check "export drape" 0 "drape" -- "$WOVEN" export "$ex" --gltf "$T/d.glb" --mesh drape "${small[@]}"
"$WOVEN" export "$ex" --gltf "$T/b.glb" "${small[@]}" -q
cmp -s "$T/a.glb" "$T/b.glb" || { echo "FAIL the same export gave different files"; fails=$((fails + 1)); }

# a finished fit's directory is read through its params.json; without one it is refused
mkdir -p "$T/fit" "$T/empty"
cp "$SRC/examples/satin.json" "$T/fit/params.json"
check "export from a fit" 0 "satin" -- "$WOVEN" export "$T/fit" --gltf "$T/f.glb" "${small[@]}"
check "no finished fit" 2 "no finished fit" -- "$WOVEN" export "$T/empty" --gltf "$T/x.glb"
echo '{"pattern": "houndstooth"}' >"$T/pattern.json"
check "unknown pattern" 2 "houndstooth" -- "$WOVEN" export "$T/pattern.json" --gltf "$T/x.glb"
check "unwritable output" 3 "$T/no/dir/x.glb" -- "$WOVEN" export "$ex" --gltf "$T/no/dir/x.glb"
check "bad extension" 1 ".glb" -- "$WOVEN" export "$ex" --gltf "$T/x.gltf"
check "bad texture size" 1 "--texture" -- "$WOVEN" export "$ex" --gltf "$T/x.glb" --texture 4
check "bad mesh" 1 "--mesh" -- "$WOVEN" export "$ex" --gltf "$T/x.glb" --mesh teapot
check "missing input" 3 "$T/none.json" -- "$WOVEN" export "$T/none.json" --gltf "$T/x.glb"
[[ -e $T/x.glb ]] && { echo "FAIL a failed export left x.glb"; fails=$((fails + 1)); }
# a failed run keeps the earlier result
cp "$T/a.glb" "$T/keep.glb"
check "invalid input keeps earlier" 2 "" -- "$WOVEN" export "$T/pattern.json" --gltf "$T/a.glb"
cmp -s "$T/a.glb" "$T/keep.glb" || { echo "FAIL a failed export changed the earlier a.glb"; fails=$((fails + 1)); }

check "view help" 0 "usage: woven view" -- "$WOVEN" view --help
check "view" 0 '"photo": false' -- "$WOVEN" view "$ex" -o "$T/v.html" --json
grep -q 'id="woven-data"' "$T/v.html" || { echo "FAIL v.html has no data"; fails=$((fails + 1)); }
grep -q '<script id="woven-viewer" type="module">' "$T/v.html" || { echo "FAIL v.html has no viewer"; fails=$((fails + 1)); }
grep -Eq '(src|href)="https?:' "$T/v.html" && { echo "FAIL v.html refers to the network"; fails=$((fails + 1)); }
"$WOVEN" render --params "$SRC/examples/satin.json" --scene flat45 --spp 1 -o "$T/fit/photo.png" -q
check "view a fit with its photo" 0 '"photo": true' -- "$WOVEN" view "$T/fit" -o "$T/f.html" --json
grep -qF 'data:image\/png;base64,' "$T/f.html" || { echo "FAIL f.html has no photo"; fails=$((fails + 1)); }
check "view cylinder" 0 "cylinder" -- "$WOVEN" view "$ex" --scene cylinder -o "$T/c.html"
check "view no finished fit" 2 "no finished fit" -- "$WOVEN" view "$T/empty" -o "$T/x.html"
echo '{"pattern": "twill", "roughness": {"warp": 7}}' >"$T/range.json"
check "view out of range" 2 "roughness.warp" -- "$WOVEN" view "$T/range.json" -o "$T/x.html"
check "view bad photo" 3 "$T/none.png" -- "$WOVEN" view "$ex" --photo "$T/none.png" -o "$T/x.html"
check "view bad extension" 1 ".html" -- "$WOVEN" view "$ex" -o "$T/x.htm"
check "view unwritable" 3 "$T/no/dir/x.html" -- "$WOVEN" view "$ex" -o "$T/no/dir/x.html"
[[ -e $T/x.html ]] && { echo "FAIL a failed view left x.html"; fails=$((fails + 1)); }
check "compare blur" 0 '"blur": 4' -- "$WOVEN" compare "$T/fit/photo.png" "$T/fit/photo.png" --blur 4 --json
check "compare bad blur" 1 "--blur" -- "$WOVEN" compare "$T/fit/photo.png" "$T/fit/photo.png" --blur -3

echo "$fails failure(s)"
[[ $fails == 0 ]]
