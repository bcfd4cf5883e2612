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
# One timed run: "wall cpu" seconds of the whole command (process start and MPI start-up
# included; cpu = user + system time of every process, the ranks included). The CPU
# time per sample does not depend on what else runs on the machine, the wall time does.
# run DIR JOBS [LAUNCHER...]
run() {
  local dir=$1 jobs=$2
  shift 2
  rm -rf "$dir"
  /usr/bin/time -f "%e %U %S" -o "$T/time" "$@" "$WOVEN" dataset --scene "$SCENE" --per-pattern "$PER" --seed 11 \
    --jobs "$jobs" -o "$dir" -q
  awk '{print $1, $2 + $3}' "$T/time"
}
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
load_before=$(load)
one=() omp=() two=() c1=() c2=() co=()
for _ in $(seq "$RUNS"); do
  read -r w c <<<"$(run "$T/one" 1)"
  one+=("$w") c1+=("$c")
  read -r w c <<<"$(run "$T/two" 1 mpirun -n 2 --bind-to core)"
  two+=("$w") c2+=("$c")
  read -r w c <<<"$(run "$T/omp" 2)"
  omp+=("$w") co+=("$c")
done
load_after=$(load)
for d in one two omp; do
  [[ -s $T/$d/dataset.json ]] || { echo '{"error": "woven dataset failed"}'; exit 1; }
done
n=$((5 * PER))
m1=$(median "${one[@]}") m2=$(median "${two[@]}") mo=$(median "${omp[@]}")
k1=$(median "${c1[@]}") k2=$(median "${c2[@]}") ko=$(median "${co[@]}")
same=false
diff -r "$T/one" "$T/two" >/dev/null && diff -r "$T/one" "$T/omp" >/dev/null && same=true
awk -v n="$n" -v m1="$m1" -v m2="$m2" -v mo="$mo" -v k1="$k1" -v k2="$k2" -v ko="$ko" -v same="$same" -v la="$load_before" -v lb="$load_after" \
  -v scene="$SCENE" -v runs="$RUNS" -v cores="$(nproc)" 'BEGIN {
  r1 = n / m1; r2 = n / m2; ro = n / mo
  printf "{\"scene\": \"%s\", \"samples\": %d, \"runs\": %d, \"cores\": %d, \"median_seconds\": {\"one_process\": %.3f, \"mpirun_n2\": %.3f, \"one_process_2_threads\": %.3f},\n", scene, n, runs, cores, m1, m2, mo
  printf " \"samples_per_s\": {\"one_process\": %.3f, \"mpirun_n2\": %.3f, \"one_process_2_threads\": %.3f},\n", r1, r2, ro
  printf " \"median_cpu_seconds\": {\"one_process\": %.3f, \"mpirun_n2\": %.3f, \"one_process_2_threads\": %.3f},\n", k1, k2, ko
  printf " \"samples_per_cpu_s\": {\"one_process\": %.3f, \"mpirun_n2\": %.3f, \"one_process_2_threads\": %.3f},\n", n / k1, n / k2, n / ko
  printf " \"mpi_speedup\": %.3f, \"mpi_parallel_efficiency\": %.3f, \"mpi_cpu_efficiency\": %.3f, \"identical_output\": %s, \"load_before\": %s, \"load_after\": %s}\n", r2 / r1, r2 / (2 * r1), k1 / k2, same, la, lb
}'
