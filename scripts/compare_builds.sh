#!/usr/bin/env bash
# Compares what two builds of woven compute: renders (capture and radiance at
# several spp on both presets), gradients (float and double), maps and the BRDF
# functions, value by value (scripts/compare_builds.c).
#   scripts/compare_builds.sh OLD_TREE NEW_TREE [WORK_DIR]
# Each tree is a source checkout built with scripts/build.sh (build/libwoven.a).
# Prints, per output, "bit-identical" or the largest relative difference.
set -euo pipefail
old=$(cd "$1" && pwd); new=$(cd "$2" && pwd)
work=${3:-$(mktemp -d)}
mkdir -p "$work"
here=$(cd "$(dirname "$0")" && pwd)
libs="-fopenmp $(pkg-config --libs libpng jansson openblas fftw3f) -ljpeg -lOpenEXRCore -lm"
for tree in "$old" "$new"; do
  tag=$([ "$tree" = "$old" ] && echo old || echo new)
  gcc -std=c11 -O2 -D_POSIX_C_SOURCE=200809L -I"$tree/include" "$here/compare_builds.c" \
      "$tree/build/libwoven.a" $libs -o "$work/compare_$tag"
  mkdir -p "$work/$tag"
  "$work/compare_$tag" dump "$work/$tag"
done
"$work/compare_new" diff "$work/old" "$work/new"
