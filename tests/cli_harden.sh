#!/usr/bin/env bash
# Hostile input at the command line: absurd numbers, outputs aimed at inputs, runs
# that fail or are killed half way, temporary files of killed runs, untrusted
# checkpoints and models. Every case: a clear message naming the file and the key,
# a meaningful exit code, no input or earlier result lost, no partial output.
# Usage: cli_harden.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"
fail() { echo "FAIL $*"; fails=$((fails + 1)); }
scene='{"name":"tiny","image":{"width":64,"height":48,"spp":2},"camera":{"position_mm":[0,0,8],"look_at_mm":[0,0,0],"vfov_deg":12},"sample":{"shape":"plane"},"light":{"position_mm":[0,8,8],"intensity":300},"response":{"encoding":"gamma","gamma":2.2},"falloff":{"type":"gaussian","sigma_px":60}}'
echo "$scene" >"$T/tiny.json"
"$WOVEN" render --params "$SRC/examples/satin.json" --scene "$T/tiny.json" -o "$T/photo.png" -q || exit 1
FIT=(--pattern satin --iters 2 --iter-spp 1 --align-radius 0 --register-radius 0)
PRED=(--scene "$T/tiny.json" --pattern twill --model "$SRC/models/fabricnet-cylinder.bin" --force) # any model will do
no_temps() { # no temporary file or directory left in $1
  find "$1" -name '*.tmp.*' | grep -q . && fail "$2: temporary files left: $(find "$1" -name '*.tmp.*')"
}
# Python rewrites a JSON file in place: jpatch FILE 'd["key"] = value'
jpatch() { python3 -c "import json,sys; f=sys.argv[1]; d=json.load(open(f)); $2; json.dump(d, open(f,'w'))" "$1"; }

# -- crops whose end overflows an int: refused with the photo's real size, also from fit.json
CROP=2147483600,0,800,48
check "predict huge crop" 2 "lies outside the 64 x 48 photo" -- "$WOVEN" predict "$T/photo.png" "${PRED[@]}" --crop $CROP -o "$T/p.json"
check "fit huge crop" 2 "lies outside the 64 x 48 photo" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" "${FIT[@]}" --crop $CROP -o "$T/cropfit"
check "capture huge crop" 2 "lies outside the 64 x 48 photo" -- "$WOVEN" capture "$T/photo.png" "${PRED[@]}" --crop $CROP -o "$T/cropcap"
check "crop beyond int" 1 "--crop" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" "${FIT[@]}" --crop 99999999999,0,8,8 -o "$T/cropfit"
mkdir "$T/cropjob"
echo "{\"kind\":\"woven-fit\",\"version\":1,\"photo\":\"$T/photo.png\",\"crop\":[2147483600,0,800,48],\"scene\":$scene,\"descriptor\":\"default\"}" >"$T/cropjob/fit.json"
check "resume huge crop" 2 "lies outside the 64 x 48 photo" -- "$WOVEN" fit --resume "$T/cropjob"
[[ -e $T/cropfit || -e $T/cropcap || -e $T/p.json ]] && fail "a refused crop left an output"

# -- scene and parameter values: range-checked, the value shown as written
echo "${scene/\"plane\"/\"plane\",\"offset_mm\":[1e300,0]}" >"$T/offset.json"
check "scene offset" 2 "'sample.offset_mm[0]' = 1e+300 is outside -10000..10000" -- "$WOVEN" render --params "$SRC/examples/satin.json" --scene "$T/offset.json" -o "$T/x.png"
echo "${scene/\[0,0,8\],\"look_at_mm\"/[0,0,1e300],\"look_at_mm\"}" >"$T/farcam.json"
check "camera far away" 2 "'camera.position_mm[2]' = 1e+300 is outside" -- "$WOVEN" render --params "$SRC/examples/satin.json" --scene "$T/farcam.json" -o "$T/x.png"
echo '{"pattern": "twill", "noise_level": -2147483649}' >"$T/q.json"
check "noise level beyond int" 2 "'noise_level' = -2147483649 is outside 0..10" -- "$WOVEN" render --params "$T/q.json" -o "$T/x.png"
echo '{"pattern": "twill", "noise_level": 2.5}' >"$T/q2.json"
check "noise level not an integer" 2 "'noise_level' must be an integer" -- "$WOVEN" render --params "$T/q2.json" -o "$T/x.png"
echo '{"pattern": "twill", "twist_deg": 60.0000000001}' >"$T/twist.json"
check "twist just over" 2 "'twist_deg' = 60.0000000001 is outside -60..60" -- "$WOVEN" render --params "$T/twist.json" -o "$T/x.png"
check "params from /dev/zero" 3 "/dev/zero: not a regular file" -- "$WOVEN" render --params /dev/zero -o "$T/x.png"
check "params a directory" 3 "is a directory" -- "$WOVEN" render --params "$T" -o "$T/x.png"
echo "${scene/\"width\":64,\"height\":48/\"width\":64,\"height\":32}" >"$T/flat.json"
check "scene below the descriptor's size" 2 "too small for a fit" -- "$WOVEN" fit "$T/photo.png" --scene "$T/flat.json" "${FIT[@]}" -o "$T/smallfit"
[[ -e $T/x.png || -e $T/smallfit ]] && fail "a refused command left an output"

# -- outputs that are inputs
cp "$T/photo.png" "$T/keep.png"
check "predict onto its photo" 2 "refusing to write over an input" -- "$WOVEN" predict "$T/photo.png" "${PRED[@]}" -o "$T/photo.png"
cmp -s "$T/photo.png" "$T/keep.png" || fail "predict -o PHOTO changed the photo"
mkdir "$T/own"
cp "$T/photo.png" "$T/own/photo.png"
check "fit into the photo's directory" 2 "lies inside this output directory" -- "$WOVEN" fit "$T/own/photo.png" --scene "$T/tiny.json" "${FIT[@]}" -o "$T/own"
cmp -s "$T/own/photo.png" "$T/keep.png" || fail "fit -o DIR replaced DIR/photo.png"
check "maps over a foreign file" 3 "not part of this output" -- "$WOVEN" maps --params "$SRC/examples/twill.json" --size 8 -o "$T/own"
check "json escapes paths" 0 "" -- "$WOVEN" render --params "$SRC/examples/twill.json" --scene "$T/tiny.json" --spp 1 -o "$T/a\"b\\c.png" --json
python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["output"] == sys.argv[2]' "$T/out" "$T/a\"b\\c.png" ||
  fail "--json output is not JSON naming the path"

# -- a maps directory that fails half way (file size limit) stays as it was
"$WOVEN" maps --params "$SRC/examples/twill.json" --size 256 --format both -o "$T/maps" -q
cp -r "$T/maps" "$T/maps.keep"
check "maps fail half way" 3 "File too large" -- bash -c "trap '' XFSZ; ulimit -f 200; exec \"\$0\" \"\$@\"" "$WOVEN" maps --params "$SRC/examples/satin.json" --size 256 --format both -o "$T/maps"
diff -r "$T/maps" "$T/maps.keep" >/dev/null || fail "a failed maps run changed the earlier maps"
no_temps "$T" "failed maps"

# -- a fit: photo recorded absolute, resumed from elsewhere; --force that fails keeps the old fit
check "fit" 0 "" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" "${FIT[@]}" -o "$T/fit" -q
python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["photo"] == sys.argv[2]' "$T/fit/fit.json" "$T/photo.png" ||
  fail "fit.json does not record the photo's absolute path"
: >"$T/fit/checkpoint.json.tmp.Old456" && touch -d '2001-01-01' "$T/fit/checkpoint.json.tmp.Old456" # a killed write
(cd / && "$WOVEN" fit --resume "$T/fit" -q) || fail "--resume from another working directory"
[[ -e $T/fit/checkpoint.json.tmp.Old456 ]] && fail "stale temporary file in the fit directory not removed"
cp -r "$T/fit" "$T/fit.keep"
check "fit --force fails at the maps" 3 "File too large" -- bash -c "trap '' XFSZ; ulimit -f 100; exec \"\$0\" \"\$@\"" "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" "${FIT[@]}" --seed 7 -o "$T/fit" --force
diff -r "$T/fit" "$T/fit.keep" >/dev/null || fail "a failed --force changed the earlier fit"
no_temps "$T" "failed fit --force"

# -- untrusted checkpoint values: refused naming the file and the key
ck() { # ck NAME NEEDLE PYTHON-EDIT
  rm -rf "$T/bad" && cp -r "$T/fit.keep" "$T/bad" && jpatch "$T/bad/checkpoint.json" "$3"
  check "$1" 2 "$2" -- "$WOVEN" fit --resume "$T/bad"
}
ck "checkpoint iter_spp" "checkpoint.json: 'opts.iter_spp' = 100000 is outside 1..4096" 'd["opts"]["iter_spp"] = 100000'
ck "checkpoint iter_scale" "checkpoint.json: 'opts.iter_scale' = 0 is outside 1..16" 'd["opts"]["iter_scale"] = 0'
ck "checkpoint down_w" "checkpoint.json: 'opts.down_w' = 0 is outside 1..1024" 'd["opts"]["down_w"] = 0'
ck "checkpoint register radius" "'opts.register_radius' = 100000 is outside 0..50" 'd["opts"]["register_radius"] = 100000'
ck "checkpoint rng" "checkpoint.json: 'rng' must be a string of 16 hexadecimal digits" 'd["rng"] = "zz"'
ck "checkpoint offset" "'registration.offset_mm[0]' = 1e+300 is outside" 'd["registration"]["offset_mm"][0] = 1e300'
ck "checkpoint iter" "'iter' = -5 is outside" 'd["iter"] = -5'

# -- a fit killed before its first periodic checkpoint can be resumed
"$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" "${FIT[@]}" --iters 100000 -o "$T/killed" -q &
pid=$!
for _ in $(seq 1000); do [[ -e $T/killed/fit.json ]] && break; sleep 0.01; done
kill -9 $pid 2>/dev/null
wait $pid 2>/dev/null
check "resume a fit killed at its start" 0 '"iterations":' -- "$WOVEN" fit --resume "$T/killed" --iters 2 --json
[[ -s $T/killed/params.json ]] || fail "the resumed fit did not finish"

# -- temporary files of killed runs: old unlocked ones go, fresh or locked ones stay
old() { mkdir -p "$(dirname "$1")" && : >"$1" && touch -d '2001-01-01' "$1"; }
old "$T/r.png.tmp.AbC123"
: >"$T/r.png.tmp.Fresh1"
old "$T/r.png.tmp.Locked"
mkdir "$T/maps.tmp.Old123" && touch -d '2001-01-01' "$T/maps.tmp.Old123"
check "render cleans its temporaries" 0 "" -- flock "$T/r.png.tmp.Locked" "$WOVEN" render --params "$SRC/examples/twill.json" --scene "$T/tiny.json" --spp 1 -o "$T/r.png" -q
[[ -e $T/r.png.tmp.AbC123 ]] && fail "stale temporary file not removed"
[[ -e $T/r.png.tmp.Fresh1 && -e $T/r.png.tmp.Locked ]] || fail "a fresh or locked temporary file was removed"
"$WOVEN" maps --params "$SRC/examples/twill.json" --size 8 -o "$T/maps" -q
[[ -e $T/maps.tmp.Old123 ]] && fail "stale temporary directory not removed"
rm -f "$T"/r.png.tmp.*

# -- dataset: a corrupt .json or a truncated .png is not a finished sample
"$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 1 -o "$T/ds" -q
echo '{' >"$T/ds/samples/plain_0.json"
head -c 100 "$T/ds/samples/satin5_0.png" >"$T/ds/samples/x" && mv "$T/ds/samples/x" "$T/ds/samples/satin5_0.png"
check "dataset redoes damaged samples" 0 '"rendered": 2' -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 1 -o "$T/ds" --json
jpatch "$T/ds/dataset.json" 'd["per_pattern"] = 1000000000'
check "dataset per_pattern" 2 "dataset.json: 'per_pattern' = 1000000000 is outside 1..1000000" -- "$WOVEN" train "$T/ds" -o "$T/m.bin"

# -- models: unknown kind, NaN weights; weights that are a directory
python3 - "$SRC/models/fabricnet-cylinder.bin" "$T" <<'EOF' || fail "could not patch a model"
import sys, zlib, struct
b = bytearray(open(sys.argv[1], 'rb').read())
def seal(b):
    b[504:508] = struct.pack('<I', zlib.crc32(bytes(b[512:]))) # format 2: a 512-byte header
    b[508:512] = struct.pack('<I', zlib.crc32(bytes(b[:508])))
k = bytearray(b); k[12:16] = struct.pack('<I', 99); seal(k)
open(sys.argv[2] + '/kind99.bin', 'wb').write(k)
n_in = struct.unpack('<I', b[48:52])[0]
w = bytearray(b); off = 512 + 8 * n_in; w[off:off + 2] = b'\x00\x7e'; seal(w) # first weight: f16 NaN
open(sys.argv[2] + '/nan.bin', 'wb').write(w)
EOF
check "model of unknown kind" 4 "kind99.bin: unknown FabricNet file kind 99" -- "$WOVEN" predict "$T/photo.png" "${PRED[@]}" --model "$T/kind99.bin" -o "$T/p.json"
check "model with NaN weights" 4 "nan.bin: layer 1 weights hold NaN" -- "$WOVEN" predict "$T/photo.png" "${PRED[@]}" --model "$T/nan.bin" -o "$T/p.json"
check "vgg19 weights a directory" 3 "is a directory" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" "${FIT[@]}" --descriptor vgg19 --vgg19-weights "$T" -o "$T/vggfit"

# -- the mesh renderer, exporters and batches: hostile files (tests/harden_inputs.py writes them)
H=$T/h
python3 "$SRC/tests/harden_inputs.py" "$H" "$SRC/examples/twill.json"
mkfifo "$H/fifo"
S=(-q --threads 1)
check "deep glTF node tree" 4 "deep.gltf: its node tree is more than 256 levels deep" -- "$WOVEN" scene "$H/s_deep.json" -o "$T/m.png" "${S[@]}"
check "PLY header declares 2e9 vertices" 5 "bomb.ply: the PLY header declares 2000000000 vertices" -- "$WOVEN" scene "$H/s_bomb.json" -o "$T/m.png" "${S[@]}"
check "binary PLY header declares 2e9 vertices" 5 "bombbin.ply: the PLY header declares 2000000000 vertices" -- "$WOVEN" scene "$H/s_bombbin.json" -o "$T/m.png" "${S[@]}"
check "GLB chunk longer than the file" 4 "bomb.glb: a GLB chunk declares 2147483632 bytes, more than the file holds" -- "$WOVEN" scene "$H/s_glb.json" -o "$T/m.png" "${S[@]}"
check "scene cannot raise its memory limit" 5 "above the memory limit of 2048 MB" -- "$WOVEN" scene "$H/s_raise.json" -o "$T/m.png" "${S[@]}"
check "scene lowers its memory limit" 5 "above the memory limit of 1 MB" -- "$WOVEN" scene "$H/s_bomb.json" -o "$T/m.png" "${S[@]}" --mesh-limit-mb 1
check "UVs of 1e20" 4 "uv1e20.obj: vertex 1 has a UV of (0, 1e+20), outside -1e+08..1e+08" -- "$WOVEN" scene "$H/s_uv.json" -o "$T/m.png" "${S[@]}"
check "coordinates of 1e10 mm" 4 "c1e10.obj: vertex 0 has a coordinate of -1e+10 mm" -- "$WOVEN" scene "$H/s_c1e10.json" -o "$T/m.png" "${S[@]}"
check "coordinates of 3e38 mm" 4 "c3e38.obj: vertex 0 has a coordinate of -3e+38 mm" -- "$WOVEN" scene "$H/s_c3e38.json" -o "$T/m.png" "${S[@]}"
check "environment radiance times strength overflows" 4 "envhuge.exr: pixel 0's radiance 3.4e+38 times the strength 1e+06 is above 1e+18" -- "$WOVEN" scene "$H/s_env.json" -o "$T/m.png" "${S[@]}"
[[ -e $T/m.png ]] && fail "a refused scene left an output"
check "glTF within the depth limit" 0 "" -- "$WOVEN" scene "$H/s_tri.json" -o "$T/tri.png" "${S[@]}"
ln -s map.exr "$H/maplink.exr"
check "one map for 8 edits" 0 "" -- "$WOVEN" scene "$H/s_edits8.json" -o "$T/e8.png" "${S[@]}"
for k in fifo_map fifo_env fifo_fab; do
  check "FIFO as ${k#fifo_}" 3 "fifo: not a regular file" -- timeout 20 "$WOVEN" scene "$H/s_$k.json" -o "$T/m.png" "${S[@]}"
done
check "FIFO as scene file" 3 "fifo: not a regular file" -- timeout 20 "$WOVEN" scene "$H/fifo" -o "$T/m.png" "${S[@]}"
check "FIFO as compare photo" 3 "fifo: not a regular file" -- timeout 20 "$WOVEN" compare "$H/fifo" "$T/photo.png"
check "FIFO as VGG-19 weights" 3 "fifo: is not a regular file" -- timeout 20 "$WOVEN" fit "$SRC/examples/photo_twill_cylinder.png" --scene cylinder --pattern twill --descriptor vgg19 --vgg19-weights "$H/fifo" -o "$T/fitfifo" --iters 1
check "fabric that is not JSON: none of its text" 4 "/etc/passwd:1:4: malformed JSON" -- "$WOVEN" scene "$H/s_passwd.json" -o "$T/m.png" "${S[@]}"
grep -q "near" "$T/err" && fail "a fabric named by a scene is quoted: $(cat "$T/err")"
truncate -s 65M "$H/big.json"
check "scene file over 64 MiB" 5 "big.json: file of 68157440 bytes is over the limit" -- "$WOVEN" scene "$H/big.json" -o "$T/m.png" "${S[@]}"
# outputs that are inputs, also through links
cp "$H/env.exr" "$T/env.keep" && cp "$H/map.exr" "$T/map.keep" && cp "$H/quad.obj" "$H/lnkt.png" && ln -s lnkt.png "$H/lnk.obj"
check "scene onto its environment map" 2 "refusing to write over an input" -- "$WOVEN" scene "$H/s_ok.json" -o "$H/env.exr" "${S[@]}"
check "scene onto its edit map" 2 "refusing to write over an input" -- "$WOVEN" scene "$H/s_ok.json" -o "$H/map.exr" "${S[@]}"
check "scene onto a mesh through a link" 2 "the output is the input" -- "$WOVEN" scene "$H/s_link.json" -o "$H/lnkt.png" "${S[@]}"
cmp -s "$H/env.exr" "$T/env.keep" && cmp -s "$H/map.exr" "$T/map.keep" && cmp -s "$H/quad.obj" "$H/lnkt.png" ||
  fail "scene -o replaced an input"
cp "$SRC/examples/twill.json" "$T/P.glb" && cp "$SRC/examples/twill.json" "$T/P.html"
check "export onto its parameter file" 2 "refusing to write over an input" -- "$WOVEN" export "$T/P.glb" --gltf "$T/P.glb" --texture 8 --directions 8 -q
check "view onto its parameter file" 2 "refusing to write over an input" -- "$WOVEN" view "$T/P.html" -o "$T/P.html" -q
cmp -s "$T/P.glb" "$SRC/examples/twill.json" && cmp -s "$T/P.html" "$SRC/examples/twill.json" || fail "export or view replaced its input"
# --json is JSON, whatever the paths and names hold
check "scene --json escapes the path" 0 "" -- "$WOVEN" scene "$H/s_ok.json" -o "$T/q\"x.png" "${S[@]}" --json
python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["output"] == sys.argv[2]' "$T/out" "$T/q\"x.png" || fail "scene --json is not JSON naming the path"
check "cloth --json escapes the path" 0 '"triangles": 8' -- "$WOVEN" cloth -o "$T/c\"d.obj" --res 2 --seconds 0.01 -q --json
python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["output"] == sys.argv[2]' "$T/out" "$T/c\"d.obj" || fail "cloth --json is not JSON"
mkdir "$T/vfit" && cp "$SRC/examples/twill.json" "$T/vfit/params.json"
echo "${scene/\"name\":\"tiny\"/\"name\":\"x\\\", \\\"photo\\\": true, \\\"y\\\": \\\"\"}" >"$T/vfit/scene.json"
check "view --json: a scene name with quotes" 0 "" -- "$WOVEN" view "$T/vfit" -o "$T/v\"w.html" -q --json
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert list(d) == ["output", "pattern", "scene", "photo"] and d["photo"] is False and d["scene"].startswith("x\""), d' "$T/out" ||
  fail "view --json copied a name raw"
check "export --json escapes the path" 0 '"relative"' -- "$WOVEN" export "$SRC/examples/twill.json" --gltf "$T/e\"f.glb" --texture 8 --directions 8 -q --json
python3 -c 'import json,sys; assert json.load(open(sys.argv[1]))["output"] == sys.argv[2]' "$T/out" "$T/e\"f.glb" || fail "export --json is not JSON"
# batches: names the batch keeps for itself; FIFOs among the photos; leftovers of killed captures
mkdir "$T/bl"
cp "$T/photo.png" "$T/bl/summary.json.png"
BATCH=(--scene "$T/tiny.json" --model "$SRC/models/fabricnet-cylinder.bin" --pattern satin --iters 1 --iter-spp 1 --align-radius 0 --register-radius 0 --drape none -q)
check "batch photo named summary.json.png" 2 "a name the batch keeps for its own files" -- "$WOVEN" capture-batch "$T/bl" -o "$T/bo" "${BATCH[@]}"
[[ -e $T/bo/summary.json ]] && fail "a refused batch wrote into its directory"
mv "$T/bl/summary.json.png" "$T/bl/a.png" && mkfifo "$T/bl/x.png"
check "batch with a FIFO among its photos: that photo fails" 2 "" -- timeout 120 "$WOVEN" capture-batch "$T/bl" -o "$T/bo" "${BATCH[@]}"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
st = {i["name"]: i["status"] for i in d["items"]}
assert st == {"a": "ok", "x": "failed"}, st' "$T/bo/summary.json" 2>/dev/null || fail "batch summary: $(cat "$T/bo/summary.json" 2>&1 | head -c 400)"
mkdir -p "$T/bo/.batch/work/a.tmp.ABC123" && touch -d '1 hour ago' "$T/bo/.batch/work/a.tmp.ABC123" "$T/bo/.batch/work"
check "batch resume (the FIFO still fails)" 2 "" -- timeout 120 "$WOVEN" capture-batch "$T/bl" -o "$T/bo" "${BATCH[@]}"
[[ -e $T/bo/.batch/work/a.tmp.ABC123 ]] && fail "a killed capture's temporary directory survived the resume"
# A hang guard only (the duplicate check is a hash set: linear by construction); no wall-clock bound.
seq -f 'p%g.png' 1 100000 >"$T/many.txt" && echo p5.png >>"$T/many.txt"
check "100,000-line list with a duplicate" 2 "would both be captured into 'p5'" -- timeout 600 "$WOVEN" capture-batch "$T/many.txt" -o "$T/bm" "${BATCH[@]}"

echo "$fails failure(s)"
[[ $fails == 0 ]]
