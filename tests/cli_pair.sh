#!/usr/bin/env bash
# `woven fit` and `woven capture` with a photo pair (--transmission): a missing, unreadable or
# wrongly sized transmission photo, a scene with no back-lit counterpart, a front-lit
# --transmission-scene and a missing or one-photo --pair-model are refused with a message naming the file or scene, writing nothing;
# a short pair fit writes photo_t.png and render_t.png, records the pair in fit.json and resumes.
# Usage: cli_pair.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"
fail() { echo "FAIL $*"; fails=$((fails + 1)); }
python3 - "$T" "$(dirname "$0")" <<'PY' || fail "could not write the test photos"
import random, sys
sys.dont_write_bytecode = True  # nothing written into the source tree
sys.path.insert(0, sys.argv[2])
from png_write import png
r = random.Random(7)  # seeded: the same photos every run
png(sys.argv[1] + '/r.png', 512, 512, [min(255, max(0, int(r.gauss(140, 30)))) for _ in range(512 * 512 * 3)])
png(sys.argv[1] + '/t.png', 512, 512, [min(255, max(0, int(r.gauss(60, 20)))) for _ in range(512 * 512 * 3)])
png(sys.argv[1] + '/big.png', 640, 640, [60] * (640 * 640 * 3))
open(sys.argv[1] + '/junk.png', 'wb').write(b'not an image at all')
PY
fit=(--pattern twill --iters 2 --align-radius 0 --register-radius 0 --distort-degree 0 --drape none
  --camera-blur 0 --no-colour-split --no-noise-sweep --threads 2)
check "missing T photo" 3 "$T/missing.png" -- "$WOVEN" fit "$T/r.png" --scene flat45 --transmission "$T/missing.png" \
  -o "$T/fitdir" "${fit[@]}"
check "unreadable T photo" 4 "$T/junk.png" -- "$WOVEN" fit "$T/r.png" --scene flat45 --transmission "$T/junk.png" \
  -o "$T/fitdir" "${fit[@]}"
check "T photo of another size" 2 "$T/big.png is 640 x 640" -- "$WOVEN" fit "$T/r.png" --scene flat45 \
  --transmission "$T/big.png" -o "$T/fitdir" "${fit[@]}"
check "capture: T photo of another size" 2 "$T/big.png is 640 x 640" -- "$WOVEN" capture "$T/r.png" --scene flat45 \
  --transmission "$T/big.png" -o "$T/fitdir" --iters 2
check "no back-lit counterpart" 2 "the scene cylinder has no built-in back-lit counterpart" -- "$WOVEN" capture \
  "$T/r.png" --scene cylinder --transmission "$T/t.png" -o "$T/fitdir"
check "front-lit transmission scene" 2 "flat45 is not a back-lit scene" -- "$WOVEN" fit "$T/r.png" --scene flat45 \
  --transmission "$T/t.png" --transmission-scene flat45 -o "$T/fitdir" "${fit[@]}"
check "--transmission-scene alone" 1 "--transmission-scene needs --transmission" -- "$WOVEN" fit "$T/r.png" \
  --scene flat45 --transmission-scene flat45-back -o "$T/fitdir" "${fit[@]}"
check "--pair-model alone" 1 "--pair-model needs --transmission" -- "$WOVEN" capture "$T/r.png" --scene flat45 \
  --pair-model "$SRC/models/fabricnet-flat45.bin" -o "$T/fitdir" --iters 2
check "missing pair model" 3 "$T/nomodel.bin" -- "$WOVEN" capture "$T/r.png" --scene flat45 --transmission "$T/t.png" \
  --pair-model "$T/nomodel.bin" -o "$T/fitdir" --iters 2
check "one-photo model as the pair model" 2 "a one-photo model, not a model for a photo pair" -- "$WOVEN" capture \
  "$T/r.png" --scene flat45 --transmission "$T/t.png" --pair-model "$SRC/models/fabricnet-flat45.bin" -o "$T/fitdir" \
  --iters 2
[[ -e $T/fitdir ]] && fail "a refused run left $T/fitdir"
check "pair fit" 0 '"ssim_rgb_fit_t"' -- "$WOVEN" fit "$T/r.png" --scene flat45 --transmission "$T/t.png" \
  -o "$T/fitdir" "${fit[@]}" --json --quiet
for f in photo_t.png render_t.png params.json; do [[ -s $T/fitdir/$f ]] || fail "the pair fit wrote no $f"; done
grep -q "\"photo\": \"$T/t.png\"" "$T/fitdir/fit.json" || fail "fit.json does not record the transmission photo"
grep -q "Transmission" "$T/fitdir/report.html" || fail "the report does not show the transmission photo"
check "pair resume" 0 '"wsc_fit_t"' -- "$WOVEN" fit --resume "$T/fitdir" --iters 3 --json --quiet
echo "$fails failure(s)"
[[ $fails == 0 ]]
