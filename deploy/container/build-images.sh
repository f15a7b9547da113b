#!/usr/bin/env bash
# Builds the container images from a host build of mpdrig (deploy/build.sh):
#   localhost/mpdrig-base:bookworm   Debian 12 from debootstrap (base-image.sh; cached)
#   localhost/mpdrig:latest          runtime: mpdrig (and mpdrig-all, which holds the commands the
#                                    mpdrig front hands over), bhp_controller, rig_echo, rig_request
#                                    + their libraries
# and prints the runtime image's size. podman caches the library layer, so a rebuild after a
# code change copies the binaries only.
#
#   BUILD_DIR=build deploy/container/build-images.sh
#   BUILD_DIR=build deploy/container/build-images.sh --dev   # and localhost/mpdrig-dev:latest,
#       the build image for students' compiled controllers (Containerfile.dev)
#
# Why the binaries come from the host build rather than a build container: the host is Debian 12
# like the image (same library versions, checked by `ldd` in the image), CI builds them anyway, and
# a second compile in a container would double CI's longest step on 2 cores (8-15 min) and pull
# ~1.1 GB of -dev packages (libsundials-dev alone brings MPI and PETSc) into an image.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
build="${BUILD_DIR:-$root/build}"
[[ "$build" = /* ]] || build="$root/$build"
source "$here/podman-env.sh"
dev=0
[[ "${1:-}" == --dev ]] && dev=1

exes=("$build/tools/mpdrig" "$build/tools/mpdrig-all" "$build/clients/bhp_controller" "$build/clients/rig_echo"
      "$build/clients/rig_request")
for exe in "${exes[@]}"; do
  [[ -x "$exe" ]] || { echo "build-images.sh: $exe not built (deploy/build.sh)" >&2; exit 1; }
done

"$here/base-image.sh"

context="$(mktemp -d /var/tmp/mpdrig-context.XXXXXX)"
trap 'rm -rf "$context"' EXIT
mkdir -p "$context/bin" "$context/etc"
cp "${exes[@]}" "$context/bin/"
strip --strip-unneeded "$context"/bin/* 2>/dev/null || true
"$here/runtime-packages.sh" "${exes[@]}" >"$context/runtime-packages.txt"
cp "$root"/deploy/cyclonedds-*.xml "$context/etc/" 2>/dev/null || true

podman_build_replacing "$MPDRIG_RUNTIME_IMAGE" --network host --build-arg BASE="$MPDRIG_BASE_IMAGE" \
  -f "$here/Containerfile.runtime" "$context"
size="$(podman image inspect --format '{{.Size}}' "$MPDRIG_RUNTIME_IMAGE")"
echo "build-images.sh: $MPDRIG_RUNTIME_IMAGE $(awk -v s="$size" 'BEGIN { printf "%.0f MB", s / 1e6 }') ($(wc -l <"$context/runtime-packages.txt") library packages)"

if [[ $dev == 1 ]]; then
  # The client SDK: what clients/ build from in the repository, at the same relative paths.
  sdk="$context/dev/sdk"
  "$here/sdk/assemble.sh" "$root" "$sdk"
  old_dev="$(podman image inspect --format '{{.Id}}' "$MPDRIG_DEV_IMAGE" 2>/dev/null || true)"
  podman_build_replacing "$MPDRIG_DEV_IMAGE" --network host --build-arg BASE="$MPDRIG_BASE_IMAGE" \
    -f "$here/Containerfile.dev" "$context/dev"
  if [[ -n "$old_dev" && "$old_dev" != "$(podman image inspect --format '{{.Id}}' "$MPDRIG_DEV_IMAGE")" ]]; then
    # cached build stages of student controllers grew on the old image and keep its layers
    podman image prune -f --filter label=org.mpdrig.image=dev >/dev/null 2>&1 || true
    podman rmi "$old_dev" >/dev/null 2>&1 || true
  fi
  size="$(podman image inspect --format '{{.Size}}' "$MPDRIG_DEV_IMAGE")"
  echo "build-images.sh: $MPDRIG_DEV_IMAGE $(awk -v s="$size" 'BEGIN { printf "%.0f MB", s / 1e6 }')"
fi
