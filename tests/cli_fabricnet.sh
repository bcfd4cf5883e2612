#!/usr/bin/env bash
# CLI behaviour of `woven dataset`, `woven train`, `woven predict` and `woven capture`:
# resume without redoing finished samples, refusing mismatched or partial datasets and
# bad models with a clear error, nothing lost. Usage: cli_fabricnet.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"
fail() { echo "FAIL $*"; fails=$((fails + 1)); }
scene='{"name":"tiny","image":{"width":64,"height":48,"spp":2},"camera":{"position_mm":[0,0,8],"look_at_mm":[0,0,0],"vfov_deg":12},"sample":{"shape":"plane"},"light":{"position_mm":[0,8,8],"intensity":300},"response":{"encoding":"gamma","gamma":2.2},"falloff":{"type":"gaussian","sigma_px":60}}'
echo "$scene" >"$T/tiny.json"
DS=$T/ds

check "dataset" 0 '"rendered": 32' -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 2 -o "$DS" --seed 3 --json
n=$(ls "$DS"/samples/*.feat | wc -l)
[[ $n == 32 ]] || fail "dataset: $n feature files, wanted 32 (16 built-ins x 2)"
[[ -s $DS/dataset.json && -s $DS/samples/twill31s_90_1.png && -s $DS/samples/satin5_0.json && -s $DS/samples/basket_1.feat ]] || fail "dataset files missing"
grep -q '"augment": 1' "$DS/dataset.json" || fail "dataset.json does not record the camera augmentation"

# Interruption: some samples lose files (as if killed before their features were
# written); a rerun redoes exactly those and leaves the others untouched.
(cd "$DS/samples" && md5sum *.json *.png *.feat | sort >"$T/before")
touch -d '2001-01-01' "$DS"/samples/*
rm "$DS/samples/plain_1.feat" "$DS/samples/satin5_1.feat" "$DS/samples/satin5_1.png" "$DS/samples/twill31s_1.json"
printf 'partial' >"$DS/samples/twill31s_90_0.feat.tmp.abcdef"
touch -d '2001-01-01' "$DS/samples/twill31s_90_0.feat.tmp.abcdef" # old and unlocked: left by a killed run
check "train refuses a partial dataset" 2 "partial" -- "$WOVEN" train "$DS" -o "$T/m.bin"
check "dataset resume" 0 '"rendered": 3' -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 2 -o "$DS" --seed 3 --json
(cd "$DS/samples" && md5sum *.json *.png *.feat | sort >"$T/after")
diff "$T/before" "$T/after" >/dev/null || fail "resumed samples differ from the first run"
new=$(find "$DS/samples" -newermt '2002-01-01' -type f | sed 's|.*/||' | sort | tr '\n' ' ')
[[ $new == "plain_1.feat plain_1.json plain_1.png satin5_1.feat satin5_1.json satin5_1.png twill31s_1.feat twill31s_1.json twill31s_1.png " ]] ||
  fail "resume rewrote '$new' (wanted only the 3 incomplete samples)"
[[ ! -e $DS/samples/twill31s_90_0.feat.tmp.abcdef ]] || fail "stale temporary file left"
check "dataset extends" 0 '"rendered": 16' -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 3 -o "$DS" --seed 3 --json
check "dataset other seed" 2 "seed" -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 3 -o "$DS" --seed 4
check "dataset other scene" 2 "scene" -- "$WOVEN" dataset --scene flat45 --per-pattern 3 -o "$DS" --seed 3
check "dataset other spp" 2 "spp" -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 3 -o "$DS" --seed 3 --spp 3
check "dataset other augmentation" 2 "augmentation" -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 3 -o "$DS" --seed 3 --no-augment
cp -r "$DS" "$T/ds_r1"
grep -q '"renderer": 3' "$T/ds_r1/dataset.json" || fail "dataset.json does not record the renderer version"
# Renderer version 2 filled the same sample grid at 2 spp (2 x 1), so its images are these;
# at 8 spp its grid (3 x 3) left a cell empty, so they are not.
cp -r "$DS" "$T/ds_r2"
sed -i 's/"renderer": 3,/"renderer": 2,/' "$T/ds_r2/dataset.json"
check "dataset extends one of renderer 2 where its grid was full" 0 '"rendered": 16' -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 4 -o "$T/ds_r2" --seed 3 --json
check "dataset at 8 spp" 0 '"rendered": 16' -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 1 -o "$T/ds_r8" --seed 3 --spp 8 --json
sed -i 's/"renderer": 3,/"renderer": 2,/' "$T/ds_r8/dataset.json"
check "dataset refuses one of renderer 2 where its grid was not full" 2 "renderer version" -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 2 -o "$T/ds_r8" --seed 3 --spp 8
sed -i '/"renderer": 3,/d' "$T/ds_r1/dataset.json" # as written by renderer version 1
check "dataset extends only with the same renderer" 2 "renderer version" -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 4 -o "$T/ds_r1" --seed 3
check "train reads an older renderer's dataset" 0 '"epochs": 1' -- "$WOVEN" train "$T/ds_r1" -o "$T/m_r1.bin" --epochs 1 --batch 4 --json
cp -r "$DS" "$T/ds_v2"
sed -i 's/"version": 2/"version": 3/' "$T/ds_v2/dataset.json"
check "dataset other version" 4 "version 3" -- "$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 3 -o "$T/ds_v2" --seed 3
check "train other version" 4 "version 3" -- "$WOVEN" train "$T/ds_v2" -o "$T/m.bin"
check "train not a dataset" 3 "not a woven dataset" -- "$WOVEN" train "$T" -o "$T/m.bin"
printf 'junk' >"$T/ds_v2/samples/plain_0.feat"
sed -i 's/"version": 3/"version": 2/' "$T/ds_v2/dataset.json"
check "train corrupt features" 4 "plain_0.feat" -- "$WOVEN" train "$T/ds_v2" -o "$T/m.bin"

# Training: loss curve, checkpoint, model; resume continues.
check "train" 0 '"epochs": 3' -- "$WOVEN" train "$DS" -o "$T/m.bin" --epochs 3 --batch 4 --json
for f in m.bin m.bin.train/checkpoint.bin m.bin.train/loss.csv m.bin.train/loss.svg m.bin.train/train.json; do
  [[ -s $T/$f ]] || fail "train output $f missing"
done
[[ $(wc -l <"$T/m.bin.train/loss.csv") == 4 ]] || fail "loss.csv should have 3 epochs"
check "train refuses to restart" 3 "--resume" -- "$WOVEN" train "$DS" -o "$T/m.bin" --epochs 3
check "train resume" 0 '"epochs": 5' -- "$WOVEN" train "$DS" -o "$T/m.bin" --epochs 5 --batch 4 --resume --json
[[ $(wc -l <"$T/m.bin.train/loss.csv") == 6 ]] || fail "loss.csv should have 5 epochs after the resume"
grep -q "^epoch,train_l1,val_l1,train_ce,val_ce,val_pattern_accuracy" "$T/m.bin.train/loss.csv" || fail "loss.csv lacks the pattern head's columns"
check "train the pattern head alone without a start" 2 "pattern head" -- "$WOVEN" train "$DS" -o "$T/h.bin" --pattern-head-only
check "train the pattern head alone" 0 '"epochs": 2' -- "$WOVEN" train "$DS" -o "$T/h.bin" --init "$T/m.bin" \
  --pattern-head-only --epochs 2 --batch 4 --json
grep -q '"pattern_head_only": true' "$T/h.bin.train/train.json" || fail "train.json does not record --pattern-head-only"
check "mix the starting head into a whole model's training" 2 "mixing" -- "$WOVEN" train "$DS" -o "$T/hm.bin" \
  --init "$T/m.bin" --head-start-weight 0.5 --epochs 2 --batch 4
check "a starting head's weight of 1" 1 "head-start-weight" -- "$WOVEN" train "$DS" -o "$T/hm.bin" \
  --init "$T/m.bin" --pattern-head-only --head-start-weight 1 --epochs 2 --batch 4
check "train the pattern head alone, mixed with the start's" 0 '"epochs": 2' -- "$WOVEN" train "$DS" -o "$T/hm.bin" \
  --init "$T/m.bin" --pattern-head-only --head-start-weight 0.5 --epochs 2 --batch 4 --json
grep -q '"head_start_weight": 0.5' "$T/hm.bin.train/train.json" || fail "train.json does not record --head-start-weight"

# Prediction and capture.
IMG=$DS/samples/twill31s_0.png
check "predict" 0 '"pattern": "twill"' -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --pattern twill --model "$T/m.bin" -o "$T/p.json" --json
check "predict output renders" 0 "" -- "$WOVEN" render --params "$T/p.json" --scene "$T/tiny.json" -o "$T/p.png" -q
# Without --pattern the pattern is chosen over the library; the JSON names it. The tiny scene
# is too small for the weave analysis: it says so and the network's pattern head decides.
check "predict chooses the pattern" 0 '"pattern_choice": {"chosen": "' -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --model "$T/m.bin" -o "$T/pc.json" --json
chosen=$(sed -n 's/.*"pattern_choice": {"chosen": "\([a-z0-9]*\)".*/\1/p' "$T/out")
[[ $chosen =~ ^(plain|basket|twill(21|22|31)[sz](_90)?|satin[58](_90)?)$ ]] || fail "predict chose '$chosen'"
grep -q "\"pattern\": \"$chosen\"" "$T/pc.json" || fail "predict output does not use the chosen pattern '$chosen'"
grep -q '"method": "network"' "$T/out" || fail "predict without a lattice did not fall back to the network"
for p in plain basket twill21s twill31z_90 satin5 satin8_90; do grep -q "\"$p\": [0-9]" "$T/out" || fail "predict JSON lacks the probability of $p"; done
grep -q '"found": false' "$T/out" || fail "predict JSON does not say the analysis found no lattice"
check "predict says why" 0 "pattern $chosen chosen" -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --model "$T/m.bin" -o "$T/pc.json"
grep -q "weave analysis: the image (64 x 48) is too small" "$T/err" || fail "predict does not say why there is no lattice"
check "predict given pattern: no choice" 0 '"pattern_choice": null' -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --pattern satin --model "$T/m.bin" -o "$T/pc.json" --json
check "predict custom pattern" 2 "custom" -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --pattern custom --model "$T/m.bin" -o "$T/pc.json"
check "predict other scene" 2 "scene-specific" -- "$WOVEN" predict "$IMG" --scene flat45 --pattern twill --model "$T/m.bin" -o "$T/p.json"
check "predict default model missing" 3 "no default model" -- env WOVEN_MODEL_DIR="$T/none" "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --pattern twill -o "$T/p.json"
check "capture" 0 '"ssim_fit"' -- "$WOVEN" capture "$IMG" --scene "$T/tiny.json" --pattern twill --model "$T/m.bin" -o "$T/cap" --iters 3 --iter-scale 1 --iter-spp 2 --json
for f in network.json params.json render.png start.png compare.png loss.svg report.html maps/normal.png fit.json checkpoint.json; do
  [[ -s $T/cap/$f ]] || fail "capture output $f missing"
done
grep -q "network" "$T/cap/report.html" || fail "report does not name the network start"
check "capture resumes as a fit" 0 '"iterations": 4' -- "$WOVEN" fit --resume "$T/cap" --iters 4 --json
check "capture chooses the pattern" 0 '"pattern_choice": {"chosen": "' -- "$WOVEN" capture "$IMG" --scene "$T/tiny.json" --model "$T/m.bin" -o "$T/capc" --iters 2 --iter-spp 2 --align-radius 0 --json
grep -q '"pattern_choice"' "$T/capc/fit.json" || fail "capture fit.json lacks the pattern choice"
# How sure the capture is: each family's best candidate and score, the blurred-copy baseline,
# how much of the photo's detail is periodic.
grep -q '"family_scores": {"[a-z]*": {"pattern": "' "$T/out" || fail "capture JSON lacks the families' scores"
grep -q '"family_score_kind": "probability"' "$T/out" || fail "capture JSON does not say what the families' scores are"
grep -q '"ssim_rgb_blurred_photo": [0-9]' "$T/out" || fail "capture JSON lacks the blurred-copy SSIM"
grep -Eq '"below_blurred_copy": (true|false)' "$T/out" || fail "capture JSON lacks the blurred-copy flag"
grep -Eq '"blas_core": "[A-Za-z0-9_]+"' "$T/out" || fail "capture JSON does not name OpenBLAS's kernels"
grep -q 'OpenBLAS kernels <code>[A-Za-z0-9_]*</code>' "$T/cap/report.html" || fail "report does not name OpenBLAS's kernels"
grep -Eq '"photo_periodic_share": (0|1)(\.[0-9]+)?[,}]' "$T/out" || fail "capture JSON lacks the photo's periodic share"
grep -q 'How the families stood' "$T/capc/report.html" || fail "capture report lacks the families' scores"
grep -q "found no weave lattice" "$T/capc/report.html" || fail "capture report does not say the analysis found no lattice"
for f in zoom.png spectra.png; do [[ -s $T/capc/$f ]] || fail "capture output $f missing"; done
check "auto capture resumes as a fit" 0 '"iterations": 3' -- "$WOVEN" fit --resume "$T/capc" --iters 3 --json

# Bad models: clear error naming the file, non-zero exit, earlier results untouched.
cp "$T/p.json" "$T/p.keep"
cp -r "$T/cap" "$T/cap.keep"
size=$(stat -c %s "$T/m.bin")
head -c $((size / 2)) "$T/m.bin" >"$T/trunc.bin"
check "truncated model" 4 "trunc.bin: truncated" -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --pattern twill --model "$T/trunc.bin" -o "$T/p.json"
cp "$T/m.bin" "$T/corrupt.bin"
printf '\x55' | dd of="$T/corrupt.bin" bs=1 seek=$((size - 100)) conv=notrunc 2>/dev/null
check "corrupt model" 4 "corrupt.bin: payload checksum mismatch" -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --pattern twill --model "$T/corrupt.bin" -o "$T/p.json"
printf 'hello' >"$T/junk.bin"
check "not a model" 4 "junk.bin: not a FabricNet model" -- "$WOVEN" capture "$IMG" --scene "$T/tiny.json" --pattern twill --model "$T/junk.bin" -o "$T/cap" --force
check "checkpoint is not a model" 4 "not a FabricNet model" -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --pattern twill --model "$T/m.bin.train/checkpoint.bin" -o "$T/p.json"
# a model made for another descriptor: patch the name and fix the header checksum
python3 - "$T/m.bin" "$T/vgg.bin" <<'EOF' || fail "could not patch a model"
import sys, zlib, struct
b = bytearray(open(sys.argv[1], 'rb').read())
b[16:48] = b'vgg19'.ljust(32, b'\0')
b[508:512] = struct.pack('<I', zlib.crc32(bytes(b[:508])))
open(sys.argv[2], 'wb').write(b)
EOF
check "model for another descriptor" 2 "vgg.bin: model made for descriptor 'vgg19'" -- "$WOVEN" predict "$IMG" --scene "$T/tiny.json" --pattern twill --model "$T/vgg.bin" -o "$T/p.json"
cmp -s "$T/p.json" "$T/p.keep" || fail "a failed predict changed its output"
diff -r "$T/cap" "$T/cap.keep" >/dev/null || fail "a failed capture changed its directory"

echo "$fails failure(s)"
[[ $fails == 0 ]]
