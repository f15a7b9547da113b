#!/usr/bin/env bash
# Soak: one `mpdrig serve` with RIGS rigs (default 10) at RATE_HZ (default 1 kHz) in real time for
# MINUTES (default 10), a bhp_controller on each rig and rig_echo recording rig-1. Reports what
# degrades over a long run: the service's deadline misses, lost periods and longest stall, its RSS
# at the start and the end (and the peak), the samples the recorder lost (gaps in its rig time),
# and how each client ended. Not a test: the numbers depend on the machine and its load.
#
#   bash bench/soak.sh                    # 10 rigs, 1 kHz, 10 minutes
#   MINUTES=1 bash bench/soak.sh          # a short run
#   MINUTES=0.5 RIGS=4 RATE_HZ=500 bash bench/soak.sh
#
# Environment: BUILD_DIR (default <repo>/build), DOMAIN (default 81), MINUTES, RIGS, RATE_HZ,
# SERVE_ARGS (more `mpdrig serve` options, e.g. "--estimate-hz 100").
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$repo/build}"
mpdrig="$build/tools/mpdrig"
controller="$build/clients/bhp_controller"
echo_exe="$build/clients/rig_echo"
for exe in "$mpdrig" "$controller" "$echo_exe"; do
  [[ -x "$exe" ]] || { echo "error: $exe not built (deploy/build.sh)" >&2; exit 1; }
done
domain="${DOMAIN:-81}"
minutes="${MINUTES:-10}"
rigs="${RIGS:-10}"
rate="${RATE_HZ:-1000}"
seconds="$(awk -v m="$minutes" 'BEGIN { printf "%d", m * 60 }')"
(( seconds >= 5 )) || { echo "error: MINUTES=$minutes is under 5 s" >&2; exit 1; }
work="$(mktemp -d)"
pids=()
cleanup() { for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$work"; }
trap cleanup EXIT INT TERM
rss_mb() { awk '/^VmRSS/ { printf "%.1f", $2 / 1024 }' "/proc/$1/status"; }
hwm_mb() { awk '/^VmHWM/ { printf "%.1f", $2 / 1024 }' "/proc/$1/status"; }

rig_args=()
for i in $(seq 1 "$rigs"); do rig_args+=(--rig "rig-$i"); done
# The rigs under heave, so the controllers have work: 0.1 m at 0.2 Hz, 5 L/min, 31 deg.
# shellcheck disable=SC2086
"$mpdrig" serve --clock realtime --rate-hz "$rate" --domain "$domain" "${rig_args[@]}" \
  --heave-amp-m 0.1 --heave-hz 0.2 --pump-lpm 5 --choke-deg 31 ${SERVE_ARGS:-} \
  2>"$work/serve.txt" &
serve_pid=$!
pids+=("$serve_pid")
"$echo_exe" --rig rig-1 --domain "$domain" --timeout 5 --out "$work/rig-1.csv" \
  2>"$work/echo.txt" &
echo_pid=$!
pids+=("$echo_pid")
controller_pids=()
for i in $(seq 1 "$rigs"); do
  "$controller" --rig "rig-$i" --domain "$domain" --timeout 5 \
    >"$work/controller-$i.out" 2>"$work/controller-$i.txt" &
  controller_pids+=($!)
  pids+=($!)
done
sleep 5
rss_start="$(rss_mb "$serve_pid")"
echo "soak: $rigs rigs at $rate Hz for $seconds s, a bhp_controller per rig, rig_echo on rig-1"
echo "service RSS at 5 s: $rss_start MB"
sleep "$(( seconds > 5 ? seconds - 5 : 0 ))"
rss_end="$(rss_mb "$serve_pid")"
rss_peak="$(hwm_mb "$serve_pid")"
echo "service RSS at end: $rss_end MB (peak $rss_peak MB)"
# The clients first (each must still be running: an exit would be a lost rig), then the service.
alive=0
for pid in "${controller_pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=$((alive + 1)); done
echo "controllers still running at the end: $alive of $rigs"
kill -INT "$echo_pid" 2>/dev/null || true
wait "$echo_pid" || echo "rig_echo ended early with status $?: $(tail -1 "$work/echo.txt")"
for pid in "${controller_pids[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
for pid in "${controller_pids[@]}"; do wait "$pid" 2>/dev/null || true; done
kill -TERM "$serve_pid"
wait "$serve_pid" || true
pids=()
grep -E "deadline misses|rig-1 ran" "$work/serve.txt" | sed 's/^mpdrig serve: /service: /'
sed -n 's/.* \([0-9]*\) samples, .*/\1/p' "$work/serve.txt" |
  awk '{ n++; s += $1 } END { printf "service: %d rigs, %d samples published in all\n", n, s }'
# Samples the recorder lost: gaps in rig-1's time beyond one period.
awk -F, -v period="$(awk -v r="$rate" 'BEGIN { print 1 / r }')" '
  /^#/ || /^time_s/ { next }
  { t = $1 + 0; if (n > 0 && t - last > 1.5 * period) lost += int((t - last) / period + 0.5) - 1;
    if (n == 0) first = t; last = t; n++ }
  END { printf "recorder (rig_echo, rig-1): %d samples, rig time %.3f..%.3f s, %d samples lost in gaps\n", n, first, last, lost }' \
  "$work/rig-1.csv"
lost_rigs="$(cat "$work"/controller-*.txt | grep -c "lost:" || true)"
echo "controllers that reported a lost rig: $lost_rigs"
cat "$work"/controller-*.txt | sed -n 's/.* \([0-9]*\) choke commands.*/\1/p' |
  awk '{ n += $1 } END { printf "controllers: %d choke commands in all\n", n }'
