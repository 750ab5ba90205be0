#!/usr/bin/env bash
# ctest farm_k8s_manifests: deploy/k8s/*.yaml validated offline against the Kubernetes API schema and the
# project's rules (deploy/k8s/validate/validate.mjs, with the npm packages pinned by its package-lock.json,
# installed into the build tree with `npm ci`). Exit 77 (skipped) only when node or npm is not installed.
# usage: k8s_manifests_test.sh SOURCE_DIR WORK_DIR
set -euo pipefail
src=$1
work=$2
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  echo "SKIP: node/npm not installed: the Kubernetes manifests are not validated"
  exit 77
fi
mkdir -p "$work"
cp "$src/deploy/k8s/validate/package.json" "$src/deploy/k8s/validate/package-lock.json" \
   "$src/deploy/k8s/validate/validate.mjs" "$work/"
cd "$work"
# Reinstall only when the lock file changed.
if ! cmp -s package-lock.json node_modules/.package-lock.stamp 2>/dev/null; then
  npm ci --no-audit --no-fund --loglevel=error
  cp package-lock.json node_modules/.package-lock.stamp
fi
node validate.mjs "$src"/deploy/k8s/*.yaml
