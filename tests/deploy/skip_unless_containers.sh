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
