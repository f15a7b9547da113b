# Sourced by the deploy/container scripts: podman with the settings of containers.conf (runc,
# explicit ulimits), and the image names they share.
here_="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
export CONTAINERS_CONF="${CONTAINERS_CONF:-$here_/containers.conf}"
MPDRIG_BASE_IMAGE="${MPDRIG_BASE_IMAGE:-localhost/mpdrig-base:bookworm}"
MPDRIG_RUNTIME_IMAGE="${MPDRIG_RUNTIME_IMAGE:-localhost/mpdrig:latest}"
MPDRIG_DEV_IMAGE="${MPDRIG_DEV_IMAGE:-localhost/mpdrig-dev:latest}"
unset here_

# podman_build_replacing TAG ARGS...: podman build -t TAG ARGS..., then removes the image TAG named
# before if nothing else uses it now, so that rebuilds (CI, each grading) leave no dangling images.
podman_build_replacing() {
  local tag="$1" old new
  shift
  old="$(podman image inspect --format '{{.Id}}' "$tag" 2>/dev/null || true)"
  podman build --quiet -t "$tag" "$@" >/dev/null || return
  new="$(podman image inspect --format '{{.Id}}' "$tag")"
  if [[ -n "$old" && "$old" != "$new" ]]; then podman rmi "$old" >/dev/null 2>&1 || true; fi
}
