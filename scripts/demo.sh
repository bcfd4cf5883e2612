#!/usr/bin/env bash
# Installs dependencies, builds, and runs the main job on the bundled example:
# renders examples/twill.json in both capture scenes and writes its texture maps.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
mkdir -p out
./build/woven render --params examples/twill.json --scene scenes/cylinder.json -o out/twill_cylinder.png
./build/woven render --params examples/twill.json --scene scenes/flat45.json -o out/twill_flat45.png
./build/woven maps --params examples/twill.json --size 512 -o out/twill_maps
echo "results in out/"
