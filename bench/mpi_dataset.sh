#!/usr/bin/env bash
# woven dataset: one process against `mpirun -n 2` (and against one process with two
# OpenMP jobs) on the same samples; samples per second, the parallel efficiency of the
# MPI run, and whether the two directories are byte for byte the same. Prints JSON.
# Usage: bench/mpi_dataset.sh WOVEN [SCENE=flat45] [PER_PATTERN=4] [RUNS=3]
set -euo pipefail
WOVEN=$1 SCENE=${2:-flat45} PER=${3:-4} RUNS=${4:-3}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader
export OMPI_MCA_btl_vader_single_copy_mechanism=none
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
load() { cut -d' ' -f1 /proc/loadavg; }
# One timed run: wall seconds of the whole command (process start and MPI start-up included).
# run DIR JOBS [LAUNCHER...]
run() {
  local dir=$1 jobs=$2
  shift 2
  rm -rf "$dir"
  local t0 t1
  t0=$(date +%s.%N)
  "$@" "$WOVEN" dataset --scene "$SCENE" --per-pattern "$PER" --seed 11 --jobs "$jobs" -o "$dir" -q
  t1=$(date +%s.%N)
  echo "$t1 - $t0" | bc -l
}
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
load_before=$(load)
one=() omp=() two=()
for _ in $(seq "$RUNS"); do
  one+=("$(run "$T/one" 1)")
  two+=("$(run "$T/two" 1 mpirun -n 2 --bind-to core)")
  omp+=("$(run "$T/omp" 2)")
done
load_after=$(load)
n=$((5 * PER))
m1=$(median "${one[@]}") m2=$(median "${two[@]}") mo=$(median "${omp[@]}")
same=false
diff -r "$T/one" "$T/two" >/dev/null && diff -r "$T/one" "$T/omp" >/dev/null && same=true
awk -v n="$n" -v m1="$m1" -v m2="$m2" -v mo="$mo" -v same="$same" -v la="$load_before" -v lb="$load_after" \
  -v scene="$SCENE" -v runs="$RUNS" -v cores="$(nproc)" 'BEGIN {
  r1 = n / m1; r2 = n / m2; ro = n / mo
  printf "{\"scene\": \"%s\", \"samples\": %d, \"runs\": %d, \"cores\": %d, \"median_seconds\": {\"one_process\": %.3f, \"mpirun_n2\": %.3f, \"one_process_2_threads\": %.3f},\n", scene, n, runs, cores, m1, m2, mo
  printf " \"samples_per_s\": {\"one_process\": %.3f, \"mpirun_n2\": %.3f, \"one_process_2_threads\": %.3f},\n", r1, r2, ro
  printf " \"mpi_speedup\": %.3f, \"mpi_parallel_efficiency\": %.3f, \"identical_output\": %s, \"load_before\": %s, \"load_after\": %s}\n", r2 / r1, r2 / (2 * r1), same, la, lb
}'
