#!/usr/bin/env bash
# Builds the Debian 12 (bookworm) base image with debootstrap and imports it into podman as
# localhost/mpdrig-base:bookworm. No image registry is involved: the root file system comes from
# the Debian mirror apt already uses. Skipped when the image exists (--rebuild forces it).
#
#   deploy/container/base-image.sh            # about 30 s on first run, then nothing
#   deploy/container/base-image.sh --rebuild
#
# Needs root (debootstrap, rootful podman). Environment: MIRROR (default: the first URIs of
# /etc/apt/sources.list.d/debian.sources, else http://deb.debian.org/debian).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source "$here/podman-env.sh"

rebuild=0
[[ "${1:-}" == --rebuild ]] && rebuild=1
if [[ $rebuild == 0 ]] && podman image exists "$MPDRIG_BASE_IMAGE"; then
  echo "base-image.sh: $MPDRIG_BASE_IMAGE exists (--rebuild to make it again)"
  exit 0
fi
[[ "$(id -u)" == 0 ]] || { echo "base-image.sh: debootstrap needs root" >&2; exit 1; }

mirror="${MIRROR:-}"
if [[ -z "$mirror" && -r /etc/apt/sources.list.d/debian.sources ]]; then
  mirror="$(awk '/^URIs:/ { print $2; exit }' /etc/apt/sources.list.d/debian.sources)"
fi
mirror="${mirror:-http://deb.debian.org/debian}"

work="$(mktemp -d /var/tmp/mpdrig-base.XXXXXX)"
trap 'rm -rf "$work"' EXIT
rootfs="$work/rootfs"
echo "base-image.sh: debootstrap bookworm from $mirror"
debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 || {
  tail -20 "$work/debootstrap.log" >&2; exit 1; }
# apt inside the image uses the host's sources when they are Debian 12's (the same package
# versions the binaries were built against, security updates included), else the mirror.
if [[ -r /etc/apt/sources.list.d/debian.sources ]] && grep -q bookworm /etc/apt/sources.list.d/debian.sources; then
  cp /etc/apt/sources.list.d/debian.sources "$rootfs/etc/apt/sources.list.d/"
  rm -f "$rootfs/etc/apt/sources.list"
else
  echo "deb $mirror bookworm main" >"$rootfs/etc/apt/sources.list"
fi
# No package caches or lists in the image.
rm -rf "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/lib/apt/lists/*
tar -C "$rootfs" -c . | podman import --quiet \
  --change 'CMD ["/bin/bash"]' --change 'ENV LANG=C.UTF-8' \
  - "$MPDRIG_BASE_IMAGE" >/dev/null
echo "base-image.sh: imported $MPDRIG_BASE_IMAGE ($(podman image inspect --format '{{.Size}}' "$MPDRIG_BASE_IMAGE" | awk '{ printf "%.0f MB", $1 / 1e6 }'))"
