#!/usr/bin/env bash
# Installs woven's build and test dependencies: Debian packages (the C libraries,
# Node.js and npm when missing, Chromium for the browser tests, NumPy, pytest and PyTorch for
# the Python package, Blender for the add-on's test, and the extra packages
# named as arguments, see scripts/install-fuzz-deps.sh), then the npm packages of web/
# (three.js, which the build embeds in the viewer; playwright-core and the Khronos glTF
# validator for the tests) with `npm ci` from the committed web/package-lock.json. No
# browser is downloaded: the tests drive /usr/bin/chromium.
set -euo pipefail
cd "$(dirname "$0")/.."
PKGS=(build-essential cmake pkg-config python3
      libpng-dev libjpeg62-turbo-dev libopenexr-dev libjansson-dev libopenblas-dev libcmocka-dev libfftw3-dev
      libassimp-dev libembree-dev libopenmpi-dev openmpi-bin chromium
      python3-numpy python3-pytest python3-torch python3-setuptools python3-venv blender "$@")
command -v node >/dev/null 2>&1 || PKGS+=(nodejs)
command -v npm >/dev/null 2>&1 || PKGS+=(npm)
missing=()
for p in "${PKGS[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
SUDO=""
[[ $(id -u) == 0 ]] || SUDO=sudo
if ((${#missing[@]})); then
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
# npm ci when the lock file changed since the last install (a stamp in node_modules).
if ! cmp -s web/package-lock.json web/node_modules/.woven-lock 2>/dev/null; then
  (cd web && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund)
  cp web/package-lock.json web/node_modules/.woven-lock
fi
