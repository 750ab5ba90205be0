#!/usr/bin/env bash
# Renders the gallery of bundled scenes shown in the README: docs/gallery/<scene>.png, one per scene in
# scenes/ (Mitsuba *.xml and pbrt-v3 *.pbrt), each with the method that suits it and a fixed seed, and
# docs/gallery/README.md (what rendered each image, how long it took). Needs a build (BUILD=build).
#   tools/gallery.sh        # a few minutes on 2 cores
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
OUT=docs/gallery
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"
# scene file | method and work (per scene: the method docs/RESULTS.md ranks best there, or bdpt)
SCENES=(
  "cornell-box.xml|--method bdpt --spp 64"
  "cornell-spheres.xml|--method bdpt --spp 64"
  "door-ajar.xml|--method mmlt --mutations-per-pixel 128"
  "glossy-plates.xml|--method pt --spp 128"
  "caustic-mirror.xml|--method mmlt --mutations-per-pixel 256"
  "textured-serialized.xml|--method bdpt --spp 64"
  "checker-spheres.pbrt|--method bdpt --spp 64"
  "furnace-sphere.xml|--method pt --spp 64"
)
{
  echo "# Gallery of the bundled scenes"
  echo
  echo "Rendered by \`tools/gallery.sh\` on $(date -u +%Y-%m-%d), commit \`$(git rev-parse --short HEAD)\`, in-process,"
  echo "$(nproc) threads, seed 1: the command shown reproduces each image exactly. Seconds: wall time on whatever"
  echo "else the machine was doing (not a benchmark; docs/RESULTS.md has the timed comparisons)."
  echo
  echo "| scene | command | seconds |"
  echo "|---|---|---|"
} > "$OUT/README.md"
for entry in "${SCENES[@]}"; do
  scene=${entry%%|*}
  args=${entry#*|}
  name=${scene%.*}
  start=$(date +%s%N)
  # shellcheck disable=SC2086
  "$BUILD/tools/mltfarm" render "scenes/$scene" $args --seed 1 --in-process -q -o "$TMP/$name.exr"
  ms=$(( ($(date +%s%N) - start) / 1000000 ))
  secs=$((ms / 1000)).$(printf %03d $((ms % 1000)))
  cp "$TMP/$name.png" "$OUT/$name.png"
  printf '| %s | `mltfarm render scenes/%s %s --seed 1 --in-process` | %s |\n' "$scene" "$scene" "$args" "$secs" >> "$OUT/README.md"
  echo "gallery: $name ($secs s)"
done
