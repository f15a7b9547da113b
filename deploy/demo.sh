#!/usr/bin/env bash
# Quick start 1: install what is missing, build, and run the virtual rig's demo.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/deploy/install-deps.sh"
BUILD_DIR="${BUILD_DIR:-$root/build}" "$root/deploy/build.sh" -DMPDRIG_BUILD_TESTS=OFF -DMPDRIG_BUILD_BENCHMARKS=OFF
mkdir -p "$root/out"
"${BUILD_DIR:-$root/build}/service/mpdrig" demo --out "$root/out/demo.csv"
