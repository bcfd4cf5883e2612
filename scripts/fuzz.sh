#!/usr/bin/env bash
# Builds the libFuzzer harnesses of fuzz/ (clang, ASan + UBSan, WOVEN_FUZZ=ON) into
# build-fuzz/ and runs each for SECONDS (default 20), one after the other. Each run
# first replays the harness's regression inputs (fuzz/regress/<harness>/), then fuzzes
# from its seeds: the repository's own files and those fuzz_make_seeds writes. Prints
# one JSON line per harness: executions, coverage (cov, ft: libFuzzer's final
# figures), corpus size and findings (files libFuzzer saved in
# build-fuzz/findings/<harness>/). Exits non-zero if any harness found anything.
#   scripts/fuzz.sh [SECONDS] [HARNESS...]    e.g. scripts/fuzz.sh 600 png jpeg
# The working corpora build-fuzz/corpus/<harness>/ persist between runs; WOVEN_FUZZ_BUILD=DIR
# builds and runs in DIR instead of build-fuzz/.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-20}
shift || true
[[ $secs =~ ^[0-9]+$ && $secs -ge 1 ]] || { echo "usage: scripts/fuzz.sh [SECONDS] [HARNESS...]" >&2; exit 1; }

scripts/install-fuzz-deps.sh
B=${WOVEN_FUZZ_BUILD:-build-fuzz} # another directory keeps a long campaign apart from a working build
CC=clang cmake -S . -B "$B" -DWOVEN_FUZZ=ON -DCMAKE_BUILD_TYPE=Debug >/dev/null
cmake --build "$B" -j2 --target fuzzers >/dev/null

# Seeds: written by fuzz_make_seeds, plus the repository's examples, scenes and golden renders.
rm -rf "$B/seeds"
"$B/fuzz/fuzz_make_seeds" "$B/seeds"
mkdir -p "$B/seeds/params" "$B/seeds/scene" "$B/seeds/exr"
mkdir -p "$B/seeds/scene3d" "$B/seeds/mesh"
cp examples/*.json "$B/seeds/params/"
cp scenes/*.json "$B/seeds/scene/"
cp scenes/*.json "$B/seeds/scene3d/"
# mesh: the first byte's low 2 bits pick the reader (0 OBJ, 1 PLY, 2 glTF, 3 GLB: 'l', 'm')
printf 'lv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nf 1/1 2/2 4/4\nf 1/1 4/4 3/3\n' >"$B/seeds/mesh/quad.obj"
printf 'mply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n' >"$B/seeds/mesh/tri.ply"
# mesh_check: the first byte's low 3 bits pick the extension (0 OBJ, 1 PLY, 2 glTF, 3 GLB, 4 STL);
# seeds: the mesh seeds, a deep node tree, header counts over the limit, a GLB chunk too long
mkdir -p "$B/seeds/mesh_check" "$B/seeds/scene3d_refs"
cp "$B/seeds/mesh/"* "$B/seeds/mesh_check/"
python3 fuzz/mesh_seeds.py "$B/seeds/mesh_check" "$B/seeds/mesh"
cp fuzz/scene3d_refs/*.json "$B/seeds/scene3d_refs/"
cp tests/golden/*.exr "$B/seeds/exr/"

if (($#)); then
  harnesses=("$@")
else
  harnesses=()
  for f in "$B"/fuzz/fuzz_*; do
    n=${f##*/fuzz_}
    # mesh runs only when named: under ASan assimp's readers take seconds an input and
    # leak or stall on malformed files inside assimp, so 20 s show assimp, not woven.
    [[ -x $f && $n != make_seeds && $n != mesh ]] && harnesses+=("$n")
  done
fi

# One OpenMP thread: the harnesses are single-threaded and idle OpenMP workers spin.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
export UBSAN_OPTIONS=print_stacktrace=1
# Harnesses that need a directory (dataset) make one per input: in memory when possible.
[[ -d /dev/shm && -w /dev/shm ]] && export TMPDIR=/dev/shm
failed=0
for h in "${harnesses[@]}"; do
  exe="$B/fuzz/fuzz_$h"
  [[ -x $exe ]] || { echo "scripts/fuzz.sh: no harness '$h'" >&2; exit 1; }
  corpus="$B/corpus/$h" findings="$B/findings/$h" log="$B/logs/$h.log"
  # mesh: leaks inside assimp's readers are assimp's (fuzz/lsan-assimp.supp); full stacks
  # let the suppression see them.
  lsan=() && [[ $h == mesh || $h == scene3d_refs ]] && lsan=(env "LSAN_OPTIONS=suppressions=$PWD/fuzz/lsan-assimp.supp"
    "ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}fast_unwind_on_malloc=0")
  mkdir -p "$corpus" "$findings" "$B/logs" "$B/seeds/$h"
  rm -f "$findings"/*
  dirs=("$corpus" "$B/seeds/$h")
  # Regression inputs: each must run clean by itself before the fuzzing starts.
  regress=0
  if [[ -d fuzz/regress/$h ]] && compgen -G "fuzz/regress/$h/*" >/dev/null; then
    regress=$(find "fuzz/regress/$h" -type f | wc -l)
    dirs+=("fuzz/regress/$h")
    if ! "${lsan[@]}" "$exe" fuzz/regress/"$h"/* >"$B/logs/$h.regress.log" 2>&1; then
      echo "scripts/fuzz.sh: $h: a regression input fails (see $B/logs/$h.regress.log)" >&2
      tail -n 30 "$B/logs/$h.regress.log" >&2
      failed=1
      continue
    fi
  fi
  # -timeout: an input taking over 60 s is a finding (an execution takes milliseconds;
  # a starved process on a busy shared machine can still stall for several seconds).
  opts=(-max_total_time="$secs" -print_final_stats=1 -timeout=60 -rss_limit_mb=2048
        -artifact_prefix="$findings/")
  case $h in params | scene | scene3d | scene3d_refs | safetensors | dataset | fit_checkpoint) opts+=(-dict=fuzz/json.dict) ;; esac
  set +e
  "${lsan[@]}" "$exe" "${opts[@]}" "${dirs[@]}" >"$log" 2>&1
  rc=$?
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  stats=$(grep -E '^#[0-9]+.*cov: ' "$log" | tail -n 1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$stats")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$stats")
  corp=$(sed -n 's/.* corp: \([0-9]*\).*/\1/p' <<<"$stats")
  # Findings: crashes, sanitizer reports, leaks, timeouts, out-of-memory. A slow unit
  # (over 10 s) is listed but is not a finding: on a shared machine it is mostly load.
  nfind=$(find "$findings" -type f ! -name 'slow-unit-*' | wc -l)
  list=$(find "$findings" -type f ! -name 'slow-unit-*' -printf '"%p",' | sed 's/,$//')
  nslow=$(find "$findings" -type f -name 'slow-unit-*' | wc -l)
  printf '{"harness": "%s", "seconds": %s, "executions": %s, "cov": %s, "ft": %s, "corpus": %s, "regression_inputs": %s, "findings": %s, "artifacts": [%s], "slow_units": %s, "exit": %s}\n' \
    "$h" "$secs" "${execs:-0}" "${cov:-0}" "${ft:-0}" "${corp:-0}" "$regress" "$nfind" "$list" "$nslow" "$rc"
  if ((rc != 0 || nfind > 0)); then
    echo "scripts/fuzz.sh: $h found a problem (log: $log):" >&2
    grep -E -A 25 '^==[0-9]+==ERROR|runtime error|^fuzz: |SUMMARY' "$log" | head -n 60 >&2 || tail -n 40 "$log" >&2
    failed=1
  fi
done
exit "$failed"
