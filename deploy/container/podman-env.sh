# Sourced by the deploy/container scripts: podman with the settings of containers.conf (runc,
# explicit ulimits), and the image names they share.
here_="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
export CONTAINERS_CONF="${CONTAINERS_CONF:-$here_/containers.conf}"
MPDRIG_BASE_IMAGE="${MPDRIG_BASE_IMAGE:-localhost/mpdrig-base:bookworm}"
MPDRIG_RUNTIME_IMAGE="${MPDRIG_RUNTIME_IMAGE:-localhost/mpdrig:latest}"
MPDRIG_DEV_IMAGE="${MPDRIG_DEV_IMAGE:-localhost/mpdrig-dev:latest}"
unset here_
