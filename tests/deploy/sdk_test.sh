#!/usr/bin/env bash
# The class SDK (deploy/container/sdk) builds a student's controller: assembled as build-images.sh
# --dev assembles it for the build image, then the example controller (which is on the client
# library, clients/client) compiled with mpdrig-build-controller, as a student's two-stage
# Containerfile does (deploy/class/cpp-controller), on this host instead of in the image: the
# same Debian 12 packages (cyclonedds-dev, libcli11-dev, libssl-dev, g++, cmake, ninja). The result must run
# and be the example controller (its --help names --lockstep and --security). Exit 77 (skipped,
# with the reason) without those tools.
#   tests/deploy/sdk_test.sh SOURCE_DIR
set -euo pipefail
src="$1"
for tool in cmake ninja g++ idlc; do
  command -v "$tool" >/dev/null || { echo "skipped: $tool not installed (Containerfile.dev's packages)"; exit 77; }
done
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$src/deploy/container/sdk/assemble.sh" "$src" "$work/sdk"
MPDRIG_SDK="$work/sdk" sh "$work/sdk/mpdrig-build-controller" "$work/student-controller" \
  "$work/sdk/clients/bhp_controller.cc" >"$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
help="$("$work/student-controller" --help)"
for option in --lockstep --security --use-estimate; do
  grep -q -- "$option" <<<"$help" || { echo "the built controller's --help lacks $option"; exit 1; }
done
echo "the SDK built the example controller: $(wc -c <"$work/student-controller") bytes"
