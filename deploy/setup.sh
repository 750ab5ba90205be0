#!/usr/bin/env bash
# Installs everything mltfarm needs to build, test and run, from Debian bookworm packages only.
# Idempotent: packages already present are skipped by apt; safe to run on every build.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libembree-dev libopenexr-dev libspdlog-dev libfmt-dev nlohmann-json3-dev libcli11-dev
  libtbb-dev libtinyobjloader-dev libstb-dev libsqlite3-dev libpng-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  prometheus-cpp-dev libcpp-httplib-dev
  chromium
  python3 python3-matplotlib python3-numpy
  iproute2 procps openssl
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  SUDO=""
  if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all packages present" >&2
fi
