#!/usr/bin/env bash
# assemble.sh ROOT OUT: the client SDK for students' compiled controllers (Containerfile.dev's
# /opt/mpdrig/sdk): what clients/ build from in the repository, at the same relative paths, so a
# controller that builds in the repository builds against the SDK unchanged. build-images.sh
# --dev puts it in the build image; tests/deploy/sdk_test.sh builds the example controller with
# it on the host.
#   idl/mpdrig.idl          the wire contract (compiled by idlc in the SDK's CMakeLists.txt)
#   service/dds/            the C++ layer over Cyclone's C API, with DDS Security
#   model/common/status.h   errors as values (header-only)
#   clients/*.h, *.cc       the example clients and their headers (clients/rig_watch.h)
#   clients/client/         the client library (rig_client.h, control_loop.h, heave_control.h):
#                           what bhp_controller and hello_controller are built on
#   clients/examples/       hello_controller.cc, a student's starting point
set -euo pipefail
root="$1" sdk="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
mkdir -p "$sdk/idl" "$sdk/service/dds" "$sdk/model/common" "$sdk/clients/client" \
  "$sdk/clients/examples"
cp "$here/CMakeLists.txt" "$here/mpdrig-build-controller" "$sdk/"
cp "$root/idl/mpdrig.idl" "$sdk/idl/"
cp "$root"/service/dds/*.h "$root"/service/dds/*.cc "$sdk/service/dds/"
cp "$root/model/common/status.h" "$sdk/model/common/"
cp "$root"/clients/*.cc "$root"/clients/*.h "$sdk/clients/"
cp "$root"/clients/client/*.h "$root"/clients/client/*.cc "$sdk/clients/client/"
cp "$root"/clients/examples/*.cc "$sdk/clients/examples/"
