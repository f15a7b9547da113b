#!/usr/bin/env bash
# Quick start 2: install what is missing, build, and run the whole test suite.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"
"$root/deploy/install-deps.sh" --containers  # the container tests run in CI too
BUILD_DIR="$build" "$root/deploy/build.sh" -DMPDRIG_BUILD_TESTS=ON -DMPDRIG_BUILD_BENCHMARKS=ON
ctest --test-dir "$build" -j"$(nproc)" --output-on-failure --timeout 900
