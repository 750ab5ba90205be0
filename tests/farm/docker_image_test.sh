#!/usr/bin/env bash
# ctest farm_docker_image: builds deploy/Dockerfile from the repository as mltfarm-local:test (the name the
# Kubernetes manifests use, never pulled) and runs the three binaries' --help in it, as the image's user.
# Exit 77 (skipped) with the reason when no container engine works here (none installed, or its daemon
# is not running).
# usage: docker_image_test.sh SOURCE_DIR
set -euo pipefail
src=$1
engine=""
for e in docker podman; do
  if command -v "$e" >/dev/null && "$e" info >/dev/null 2>&1; then engine=$e; break; fi
done
if [ -z "$engine" ]; then
  echo "SKIP: no working container engine (docker/podman missing or its daemon not running): the image is not built"
  exit 77
fi
tag=mltfarm-local:test
"$engine" build -f "$src/deploy/Dockerfile" -t "$tag" "$src"
for bin in mltfarm mltfarm-coordinator mltfarm-worker; do
  "$engine" run --rm "$tag" "$bin" --help >/dev/null
done
[ "$("$engine" run --rm "$tag" id -u)" = 65534 ] || { echo "FAIL: the image does not run as 65534"; exit 1; }
echo "image $tag built and runs"
