#!/usr/bin/env bash
# Prints the Debian packages that hold the shared libraries the given executables load (ldd), one
# a line: the runtime image installs exactly these (runtime libraries, never -dev packages), so
# the list follows the build's real dependencies instead of a hand-kept copy.
#
#   deploy/container/runtime-packages.sh build/tools/mpdrig build/clients/rig_echo ...
set -euo pipefail
(( $# > 0 )) || { echo "usage: runtime-packages.sh EXECUTABLE..." >&2; exit 2; }
libs="$(ldd "$@" | awk '/=> not found/ { print "MISSING " $1; next } /=> \// { print $3 }' | sort -u)"
if grep -q '^MISSING' <<<"$libs"; then
  echo "runtime-packages.sh: libraries not found: $(grep '^MISSING' <<<"$libs" | cut -d' ' -f2 | tr '\n' ' ')" >&2
  exit 1
fi
owner() {  # dpkg knows a file by the path its package installed; /usr is merged on Debian 12
  local path="$1" real
  real="$(readlink -f "$path")"
  for candidate in "$path" "$real" "/usr$path" "/usr$real" "${path#/usr}" "${real#/usr}"; do
    dpkg -S "$candidate" 2>/dev/null | head -1 | cut -d: -f1 && return 0
  done
  echo "runtime-packages.sh: no package owns $path" >&2
  return 1
}
while read -r lib; do owner "$lib"; done <<<"$libs" | sort -u
