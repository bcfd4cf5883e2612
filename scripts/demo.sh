#!/usr/bin/env bash
# Installs dependencies, builds, and runs the main job on the bundled example:
# captures the bundled photo examples/photo_twill_cylinder.png (FabricNet's estimate, then
# the fit), shows the captured fabric on the bundled draped cloth under the studio
# environment, renders examples/twill.json in both capture scenes and writes its texture maps,
# then the capture as glTF on a draped sheet and as the WebGL viewer.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh woven   # the program alone: the demo runs no test or benchmark
mkdir -p out
# The whole product in one command. 60 fit iterations instead of 200 keep the demo at a
# few minutes on 2 cores; drop --iters for the full fit.
./build/woven capture examples/photo_twill_cylinder.png --scene cylinder --pattern twill -o out/capture --iters 60 --force
# The capture on the draped cloth under new light, scenes/drape-studio.json at 1024 x 768.
./build/woven scene scenes/drape-studio.json --params out/capture/params.json -o out/capture_drape_studio.png
./build/woven render --params examples/twill.json --scene scenes/cylinder.json -o out/twill_cylinder.png
./build/woven render --params examples/twill.json --scene scenes/flat45.json -o out/twill_flat45.png
./build/woven maps --params examples/twill.json --size 512 -o out/twill_maps
# Into other tools: the capture as glTF on the draped sheet, and the WebGL viewer
./build/woven export out/capture --gltf out/capture_drape.glb --mesh drape
./build/woven view out/capture -o out/capture_viewer.html
echo "results in out/"
