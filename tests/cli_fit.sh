#!/usr/bin/env bash
# CLI behaviour of `woven fit` and `woven compare`: outputs, resume, bad input,
# nothing in the output directory overwritten on failure. Usage: cli_fit.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"
scene='{"name":"tiny","image":{"width":64,"height":48,"spp":8},"camera":{"position_mm":[0,0,8],"look_at_mm":[0,0,0],"vfov_deg":12},"sample":{"shape":"plane"},"light":{"position_mm":[0,8,8],"intensity":300},"response":{"encoding":"gamma","gamma":2.2},"falloff":{"type":"gaussian","sigma_px":60}}'
echo "$scene" >"$T/tiny.json"
"$WOVEN" render --params "$SRC/examples/satin.json" --scene "$T/tiny.json" -o "$T/photo.png" -q || exit 1

check "fit" 0 '"ssim_fit"' -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit" --iters 6 --iter-scale 1 --iter-spp 2 --json
for f in params.json render.png compare.png loss.svg report.html viewer.html drape.png maps/normal.png fit.json checkpoint.json scene.json; do
  [[ -s $T/fit/$f ]] || { echo "FAIL fit output $f missing"; fails=$((fails + 1)); }
done
grep -q "<svg" "$T/fit/loss.svg" || { echo "FAIL loss.svg is not SVG"; fails=$((fails + 1)); }
grep -q "data:image/png;base64," "$T/fit/report.html" || { echo "FAIL report.html does not embed images"; fails=$((fails + 1)); }
grep -q '<iframe src="viewer.html"' "$T/fit/report.html" || { echo "FAIL report.html does not embed the viewer"; fails=$((fails + 1)); }
grep -q 'alt="drape"' "$T/fit/report.html" || { echo "FAIL report.html does not show the drape"; fails=$((fails + 1)); }
# the drape is the bundled draped cloth at 512 x 384
[[ $(od -An -tx1 -j16 -N8 "$T/fit/drape.png" | tr -d ' \n') == 0000020000000180 ]] || { echo "FAIL drape.png is not 512 x 384"; fails=$((fails + 1)); }
# the fit's scene.json (the registered offset) re-renders render.png exactly
check "render the fit" 0 "" -- "$WOVEN" render --params "$T/fit/params.json" --scene "$T/fit/scene.json" -o "$T/refit.png" -q
check "re-render equals render.png" 0 '"mae": 0.0,' -- "$WOVEN" compare "$T/refit.png" "$T/fit/render.png" --json
check "compare" 0 '"ssim"' -- "$WOVEN" compare "$T/photo.png" "$T/fit/render.png" --json
check "resume further" 0 '"iterations": 9' -- "$WOVEN" fit --resume "$T/fit" --iters 9 --json
check "resume finished" 0 '"iterations": 9' -- "$WOVEN" fit --resume "$T/fit" --json

# bad input: clear error, non-zero exit, nothing in the directory touched
cp -r "$T/fit" "$T/keep"
check "refuses to overwrite" 3 "--force" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit"
printf 'not an image at all' >"$T/corrupt.png"
check "corrupt photo" 4 "corrupt.png" -- "$WOVEN" fit "$T/corrupt.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit" --force
check "missing photo" 3 "nothere.png" -- "$WOVEN" fit "$T/nothere.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit" --force
check "photo too small" 2 "much smaller" -- "$WOVEN" fit "$T/photo.png" --scene cylinder --pattern satin -o "$T/fit" --force
check "init and pattern disagree" 2 "disagrees" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" --init "$SRC/examples/twill.json" --pattern satin -o "$T/fit" --force
check "resume not a fit" 2 "not a fit directory" -- "$WOVEN" fit --resume "$T"
echo "${scene/\"width\":64,\"height\":48/\"width\":20,\"height\":20}" >"$T/too_small.json"
check "scene too small" 2 "too small for a fit" -- "$WOVEN" fit "$T/photo.png" --scene "$T/too_small.json" --pattern satin -o "$T/fit" --force
check "bad crop" 1 "--crop" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit" --crop 1,2,3
check "unknown descriptor" 2 "descriptor" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit" --force --descriptor alexnet
check "drape scene missing" 3 "nodrape.json" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit_nd" --iters 1 --drape "$T/nodrape.json"
[[ -e $T/fit_nd ]] && { echo "FAIL a refused drape scene left $T/fit_nd"; fails=$((fails + 1)); }
check "no drape" 0 "" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit_nd" --iters 1 --iter-spp 1 --align-radius 0 --register-radius 0 --drape none -q
[[ -e $T/fit_nd/drape.png ]] && { echo "FAIL --drape none wrote drape.png"; fails=$((fails + 1)); }
check "vgg19 without weights" 2 "weights" -- "$WOVEN" fit "$T/photo.png" --scene "$T/tiny.json" --pattern satin -o "$T/fit" --force --descriptor vgg19
diff -r "$T/fit" "$T/keep" >/dev/null || { echo "FAIL a failed run changed the fit directory"; fails=$((fails + 1)); }
check "compare sizes" 2 "differ in size" -- "$WOVEN" compare "$T/photo.png" "$T/fit/compare.png"

echo "$fails failure(s)"
[[ $fails == 0 ]]
