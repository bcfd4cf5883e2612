#!/usr/bin/env bash
# Installs what the fuzzers need beyond woven's own dependencies, from Debian's
# archive: clang, its runtime libraries (libFuzzer, ASan, UBSan), its OpenMP runtime
# and llvm-symbolizer (readable stack traces in reports).
set -euo pipefail
exec "$(dirname "$0")/install-deps.sh" clang libclang-rt-dev libomp-dev llvm
