#!/usr/bin/env bash
# What a stranger can make the service hold: one `mpdrig serve` (one rig, real time, RATE_HZ,
# default 1 kHz) and mpdrig_unknown_id_flood writing COUNT pump commands for distinct unknown rig
# ids (default 100000), holding its writer HOLD_S seconds, then deleting it. Prints the service's
# RSS before, while the writer lives and after, and the service's own summary: deadline misses,
# lost periods and the longest stall (the tick that met the instances losing their writer).
#
#   bash bench/unknown_id_flood.sh
#   COUNT=200000 bash bench/unknown_id_flood.sh
#   DISPOSE=1 bash bench/unknown_id_flood.sh
#   COUNT=10 ID_BYTES=10000000 bash bench/unknown_id_flood.sh   # ten 10 MB ids
#
# DISPOSE=1: the ids are disposed (key-only messages, which the topic filters do not see).
# Environment: BUILD_DIR (default <repo>/build, with -DMPDRIG_BUILD_BENCHMARKS=ON), DOMAIN
# (default 79), COUNT, HOLD_S (default 3), RATE_HZ, ID_BYTES (pad each id to this many bytes).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$repo/build}"
mpdrig="$build/tools/mpdrig"
flood="$build/bench/mpdrig_unknown_id_flood"
for exe in "$mpdrig" "$flood"; do
  [[ -x "$exe" ]] || { echo "error: $exe not built (deploy/build.sh -DMPDRIG_BUILD_BENCHMARKS=ON)" >&2; exit 1; }
done
domain="${DOMAIN:-79}"
count="${COUNT:-100000}"
hold="${HOLD_S:-3}"
rate="${RATE_HZ:-1000}"
work="$(mktemp -d)"
serve_pid=""
cleanup() { [[ -n "$serve_pid" ]] && kill "$serve_pid" 2>/dev/null; wait 2>/dev/null || true; rm -rf "$work"; }
trap cleanup EXIT INT TERM
rss_mb() { awk '/^VmRSS/ { printf "%.1f", $2 / 1024 }' "/proc/$1/status"; }

"$mpdrig" serve --clock realtime --rate-hz "$rate" --domain "$domain" --rig rig-1 \
  2>"$work/serve.txt" &
serve_pid=$!
sleep 2
echo "service RSS before:            $(rss_mb "$serve_pid") MB"
"$flood" --domain "$domain" --count "$count" --hold "$hold" --id-bytes "${ID_BYTES:-0}" \
  ${DISPOSE:+--dispose} 2>"$work/flood.txt" &
flood_pid=$!
until grep -qE "written|disposed" "$work/flood.txt" 2>/dev/null; do
  kill -0 "$flood_pid" 2>/dev/null || break
  sleep 0.1
done
sleep 1
echo "service RSS, $count ids held:  $(rss_mb "$serve_pid") MB"
wait "$flood_pid" || { cat "$work/flood.txt" >&2; exit 1; }
sleep 2
echo "service RSS, writer gone:      $(rss_mb "$serve_pid") MB"
kill -TERM "$serve_pid"
wait "$serve_pid" || true
serve_pid=""
cat "$work/flood.txt"
grep -E "deadline misses|commands refused" "$work/serve.txt"
