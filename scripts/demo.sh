#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh), then renders the default demo scene.
# Usage: scripts/demo.sh [SCENE] (default: data/scenes/glow.json)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh build
SCENE=${1:-data/scenes/glow.json}
name=$(basename "$SCENE" .json)
mkdir -p out
build/bin/scatterlab render "$SCENE" -o "out/$name.exr" --png "out/$name.png" --stats "out/$name.stats.json"
echo "demo image: $(pwd)/out/$name.exr (linear HDR) and $(pwd)/out/$name.png (sRGB preview)"
