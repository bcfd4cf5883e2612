#!/usr/bin/env bash
# woven dataset under mpirun: the same directory as one process makes, a resume after a
# kill with another process count, the directory lock, mismatched options refused.
# Usage: cli_mpi.sh WOVEN SOURCE_DIR. Exits 77 (skipped) without MPI.
source "$(dirname "$0")/cli_lib.bash"
fail() { echo "FAIL $*"; fails=$((fails + 1)); }
if [[ ${WOVEN_TEST_MPI:-OFF} != ON ]] || ! command -v mpirun >/dev/null; then
  echo "skipped: woven built without MPI or no mpirun"
  exit 77
fi
# OpenMPI refuses root unless told; the tests run as whoever runs ctest.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1
# Under the sanitizer build the ranks keep leak checks off: the MPI runtime's plug-ins
# are unloaded before the leak check runs, so their allocations cannot be attributed.
MPI=(env "ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" mpirun -n 2 --oversubscribe --bind-to none)
scene='{"name":"tiny","image":{"width":48,"height":48,"spp":1},"camera":{"position_mm":[0,0,8],"look_at_mm":[0,0,0],"vfov_deg":12},"sample":{"shape":"plane"},"light":{"position_mm":[0,8,8],"intensity":300},"response":{"encoding":"gamma","gamma":2.2},"falloff":{"type":"gaussian","sigma_px":60}}'
echo "$scene" >"$T/tiny.json"
ds() { "$WOVEN" dataset --scene "$T/tiny.json" --seed 5 --jobs 1 "$@"; }

# One process and two make the same bytes.
check "dataset, one process" 0 '"rendered": 48' -- ds --per-pattern 3 -o "$T/one" --json
check "dataset, mpirun -n 2" 0 '"processes": 2' -- "${MPI[@]}" "$WOVEN" dataset --scene "$T/tiny.json" --seed 5 \
  --jobs 1 --per-pattern 3 -o "$T/two" --json
grep -q '"rendered": 48' "$T/out" || fail "mpirun -n 2 did not render all 48 samples: $(cat "$T/out")"
diff -r "$T/one" "$T/two" >/dev/null || fail "mpirun -n 2 wrote other bytes than one process"
[[ ! -e $T/two/woven.lock ]] || fail "the lock outlived the job"

# A job killed while writing (samples missing, a truncated PNG, a temporary file, the
# lock of its dead rank 0) resumes with another process count to the same bytes.
cp -r "$T/two" "$T/killed"
rm "$T/killed/samples/plain_1.feat" "$T/killed/samples/satin5_2.png" "$T/killed/samples/twill31s_2."*
head -c 100 "$T/one/samples/twill31s_90_1.png" >"$T/killed/samples/twill31s_90_1.png"
echo partial >"$T/killed/samples/satin5_90_0.png.tmp.Ab12Cd"
touch -d '1 hour ago' "$T/killed/samples/satin5_90_0.png.tmp.Ab12Cd"
sh -c 'exit 0' & dead=$!
wait $dead
echo "$(hostname) $dead" >"$T/killed/woven.lock"
check "resume, mpirun -n 2" 0 "stale lock" -- "${MPI[@]}" "$WOVEN" dataset --scene "$T/tiny.json" --seed 5 \
  --jobs 1 --per-pattern 3 -o "$T/killed"
"$WOVEN" dataset --scene "$T/tiny.json" --seed 5 --per-pattern 3 -o "$T/killed" --json >"$T/again" 2>&1
grep -q '"rendered": 0' "$T/again" || fail "a resumed dataset was not complete: $(cat "$T/again")"
diff -r "$T/one" "$T/killed" >/dev/null || fail "the resumed dataset differs from one process's"

# A real kill: mpirun stopped mid-run, resumed by one process, then extended by two.
"${MPI[@]}" "$WOVEN" dataset --scene "$T/tiny.json" --seed 5 --jobs 1 --per-pattern 13 -o "$T/k" -q \
  >/dev/null 2>&1 &
job=$!
for _ in $(seq 400); do
  (($(find "$T/k/samples" -name '*.feat' 2>/dev/null | wc -l) >= 10)) && break
  sleep 0.05
done
kill -TERM $job 2>/dev/null
wait $job 2>/dev/null
# mpirun can return before its ranks have exited; the resume waits for the lock's holder.
holder=$(awk '{print $2}' "$T/k/woven.lock" 2>/dev/null)
for _ in $(seq 600); do
  [[ -n $holder ]] && kill -0 "$holder" 2>/dev/null || break
  sleep 0.05
done
check "resume after a kill, one process" 0 '"samples": 208' -- ds --per-pattern 13 -o "$T/k" --json
check "extend, mpirun -n 2" 0 '"rendered"' -- "${MPI[@]}" "$WOVEN" dataset --scene "$T/tiny.json" --seed 5 \
  --jobs 1 --per-pattern 15 -o "$T/k" --json
grep -q '"rendered": 32' "$T/out" || fail "the resumed job was not complete: $(cat "$T/out")"
for f in "$T/one/samples/"*; do cmp -s "$f" "$T/k/samples/${f##*/}" || fail "killed and resumed: ${f##*/} differs"; done

# One job per directory.
echo "$(hostname) $$" >"$T/one/woven.lock"
check "lock: a second job is refused" 3 "in use by another woven job" -- ds --per-pattern 3 -o "$T/one"
check "lock: also under mpirun" 3 "in use by another woven job" -- "${MPI[@]}" "$WOVEN" dataset \
  --scene "$T/tiny.json" --seed 5 --per-pattern 3 -o "$T/one"
echo "otherhost.example 4242" >"$T/one/woven.lock"
check "lock: another host's lock" 3 "remove the lock file" -- ds --per-pattern 3 -o "$T/one"
[[ -e $T/one/woven.lock ]] || fail "a refused job removed the lock"
rm "$T/one/woven.lock"

# A resume with other settings is refused on every process count.
check "mismatched seed under mpirun" 2 "another seed" -- "${MPI[@]}" "$WOVEN" dataset --scene "$T/tiny.json" \
  --seed 6 --per-pattern 3 -o "$T/one"
diff -r "$T/one" "$T/two" >/dev/null || fail "a refused job changed the directory"

exit $((fails > 0))
