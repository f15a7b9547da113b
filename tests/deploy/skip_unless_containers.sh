# Sourced by the container tests: exits with 77 (ctest's SKIP_RETURN_CODE for these tests) and
# says why when this machine cannot run them. Never a silent pass.
skip() { echo "skipped: $*"; exit 77; }
need_root() {
  [[ "$(id -u)" == 0 ]] || skip "needs root ($1); run as root or use a machine where it is"
}
need_commands() {
  local missing=()
  for c in "$@"; do command -v "$c" >/dev/null || missing+=("$c"); done
  (( ${#missing[@]} == 0 )) || skip "not installed: ${missing[*]} (deploy/install-deps.sh --containers installs them)"
}
# The base image needs the Debian mirror; a machine without either cannot build images.
need_base_image_or_mirror() {
  podman image exists "$MPDRIG_BASE_IMAGE" && return 0
  local mirror host
  mirror="$(awk '/^URIs:/ { print $2; exit }' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)"
  host="$(sed -E 's|^[a-z]+://([^/:]+).*|\1|' <<<"${mirror:-http://deb.debian.org/debian}")"
  getent hosts "$host" >/dev/null || skip "no base image and the Debian mirror $host does not resolve"
}
