#!/usr/bin/env bash
# Installs what the fuzzers need beyond scripts/install-deps.sh, from Debian's archive:
# clang, its runtime libraries (libFuzzer, ASan, UBSan), its OpenMP runtime and
# llvm-symbolizer (readable stack traces in reports).
set -euo pipefail
"$(dirname "$0")/install-deps.sh"
PKGS=(clang libclang-rt-dev libomp-dev llvm)
missing=()
for p in "${PKGS[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if ((${#missing[@]})); then
  SUDO=""
  [[ $(id -u) == 0 ]] || SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
