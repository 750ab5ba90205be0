#!/usr/bin/env bash
# Installs dependencies (idempotent), builds, and renders the bundled default scene (the Cornell box)
# to cornell-box.exr + cornell-box.png. Extra arguments are passed to `mltfarm render`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
./build/tools/mltfarm render scenes/cornell-box.xml --method mmlt --mutations-per-pixel 256 -o cornell-box.exr "$@"
