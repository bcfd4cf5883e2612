#!/usr/bin/env bash
# Installs woven's build and test dependencies from Debian's archive.
set -euo pipefail
PKGS=(build-essential cmake pkg-config python3
      libpng-dev libjpeg62-turbo-dev libopenexr-dev libjansson-dev libopenblas-dev libcmocka-dev libfftw3-dev
      libassimp-dev libembree-dev libopenmpi-dev openmpi-bin)
missing=()
for p in "${PKGS[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if ((${#missing[@]})); then
  SUDO=""
  [[ $(id -u) == 0 ]] || SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
