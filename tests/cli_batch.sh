#!/usr/bin/env bash
# woven capture-batch: one capture per photo (the same files as woven capture), a failed
# photo recorded and skipped, resume without redoing finished photos, the summary, the
# lock; under mpirun -n 2 when woven is built with MPI. Usage: cli_batch.sh WOVEN SOURCE_DIR
source "$(dirname "$0")/cli_lib.bash"
fail() { echo "FAIL $*"; fails=$((fails + 1)); }
RUN=()
if [[ ${WOVEN_TEST_MPI:-OFF} == ON ]] && command -v mpirun >/dev/null; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader
  export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1
  # Under the sanitizer build the ranks keep leak checks off: the MPI runtime's plug-ins
  # are unloaded before the leak check runs, so their allocations cannot be attributed.
  RUN=(env "ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" mpirun -n 2 --oversubscribe --bind-to none)
fi
scene='{"name":"tiny","image":{"width":64,"height":48,"spp":1},"camera":{"position_mm":[0,0,8],"look_at_mm":[0,0,0],"vfov_deg":12},"sample":{"shape":"plane"},"light":{"position_mm":[0,8,8],"intensity":300},"response":{"encoding":"gamma","gamma":2.2},"falloff":{"type":"gaussian","sigma_px":60}}'
echo "$scene" >"$T/tiny.json"
"$WOVEN" dataset --scene "$T/tiny.json" --per-pattern 2 -o "$T/ds" --seed 3 -q || fail "dataset"
"$WOVEN" train "$T/ds" -o "$T/m.bin" --epochs 1 --batch 4 -q || fail "train"
OPTS=(--scene "$T/tiny.json" --model "$T/m.bin" --pattern twill --iters 1 --iter-scale 1 --iter-spp 1 --align-radius 0
  --register-radius 0 --threads 1 --drape none)
mkdir "$T/photos"
cp "$T/ds/samples/twill31s_0.png" "$T/photos/a.png"
cp "$T/ds/samples/satin5_0.png" "$T/photos/b.png"
echo "not an image" >"$T/photos/c.png"

check "batch with an unreadable photo" 2 '"failed": 1' -- "${RUN[@]}" "$WOVEN" capture-batch "$T/photos" -o "$T/bout" \
  "${OPTS[@]}" --json
grep -q '"captured": 2' "$T/out" || fail "batch did not capture the two good photos: $(cat "$T/out")"
grep -q "c.*FAILED.*not a PNG" "$T/err" || fail "batch did not report the bad photo: $(cat "$T/err")"
for f in a/params.json a/report.html a/compare.png b/params.json summary.json summary.html; do
  [[ -s $T/bout/$f ]] || fail "batch output $f missing"
done
[[ ! -e $T/bout/c ]] || fail "a failed photo left a directory"
[[ ! -e $T/bout/woven.lock ]] || fail "the lock outlived the batch"
grep -q '"status": "failed"' "$T/bout/summary.json" || fail "summary.json lacks the failure"
grep -q '"ssim_fit": 0\.' "$T/bout/summary.json" || fail "summary.json lacks the SSIM"
grep -q "not a PNG, JPEG or EXR" "$T/bout/summary.html" || fail "summary.html lacks the reason of the failure"
# A photo's directory holds what woven capture makes of it.
"$WOVEN" capture "$T/photos/a.png" -o "$T/single" "${OPTS[@]}" -q || fail "single capture"
cmp -s "$T/single/params.json" "$T/bout/a/params.json" || fail "batch and woven capture differ on a.png"

# Resume from a list file: finished photos are not redone, the fixed one is captured.
cp "$T/ds/samples/plain_0.png" "$T/photos/c.png"
printf '# the batch\nphotos/a.png\n\nphotos/b.png\n%s\n' "$T/photos/c.png" >"$T/list.txt"
inode=$(stat -c %i "$T/bout/a")
check "batch resume" 0 '"done_before": 2' -- "${RUN[@]}" "$WOVEN" capture-batch "$T/list.txt" -o "$T/bout" "${OPTS[@]}" \
  --json
grep -q '"captured": 1' "$T/out" || fail "batch resume did not capture just the fixed photo: $(cat "$T/out")"
[[ $(stat -c %i "$T/bout/a") == "$inode" ]] || fail "batch resume redid a finished photo"
grep -q '"ok": 3' "$T/bout/summary.json" || fail "summary after the resume: $(cat "$T/bout/summary.json")"

# Bad input.
echo "$(hostname) $$" >"$T/bout/woven.lock"
check "batch lock" 3 "in use by another woven job" -- "${RUN[@]}" "$WOVEN" capture-batch "$T/photos" -o "$T/bout" "${OPTS[@]}"
rm "$T/bout/woven.lock"
mkdir "$T/other"
cp "$T/photos/a.png" "$T/other/a.jpg"
printf 'photos/a.png\nother/a.jpg\n' >"$T/dup.txt"
check "batch same names" 2 "rename one" -- "$WOVEN" capture-batch "$T/dup.txt" -o "$T/out2" "${OPTS[@]}"
check "batch no scene" 1 "--scene" -- "$WOVEN" capture-batch "$T/photos" -o "$T/out2"
check "batch unknown option" 1 "unknown option" -- "$WOVEN" capture-batch "$T/photos" -o "$T/out2" "${OPTS[@]}" --bogus
check "batch missing list" 3 "cannot read the photo list" -- "$WOVEN" capture-batch "$T/nope" -o "$T/out2" "${OPTS[@]}"
exit $((fails > 0))
