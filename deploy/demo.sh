#!/usr/bin/env bash
# Quick start 1: install what is missing, build, and run the virtual rig as a DDS service under
# heave, with the example controller holding the bottom-hole pressure.
#
#   ./deploy/demo.sh                  # one minute, then everything stops
#   ./deploy/demo.sh --duration 300   # longer (0: until Ctrl-C)
#   ./deploy/demo.sh --domain 5       # another DDS domain (default 0)
#   ./deploy/demo.sh --port 8081      # the dashboard's port (default 8080)
#
# What runs (loopback DDS only, real time, 100 Hz):
#   mpdrig serve      rig-1 and rig-2, both heaved 0.1 m at 0.2 Hz, 5 L/min through a 31 deg choke
#   bhp_controller    holds rig-1's bottom-hole pressure with the choke (rig-2 keeps it fixed)
#   rig_echo          records rig-1 as a rig log in out/demo.csv
#   mpdrig shadow     the model beside rig-1, with its error over a sliding window
#   dashboard         the live web page: open http://127.0.0.1:8080/ in a browser
# Ctrl-C stops them all. `mpdrig demo` is the same rig offline, without DDS.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"

duration=60
domain=0
port=8080
while [[ $# -gt 0 ]]; do
  case "$1" in
    --duration) duration="$2"; shift 2 ;;
    --domain) domain="$2"; shift 2 ;;
    --port) port="$2"; shift 2 ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "deploy/demo.sh: unknown option $1 (try --help)" >&2; exit 2 ;;
  esac
done
[[ "$duration" =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "--duration takes seconds" >&2; exit 2; }
[[ "$domain" =~ ^[0-9]+$ ]] || { echo "--domain takes a number" >&2; exit 2; }
[[ "$port" =~ ^[0-9]+$ ]] || { echo "--port takes a number" >&2; exit 2; }

if [[ "${SKIP_BUILD:-0}" != 1 ]]; then  # SKIP_BUILD=1: use what is in $BUILD_DIR
  "$root/deploy/install-deps.sh"
  BUILD_DIR="$build" "$root/deploy/build.sh" -DMPDRIG_BUILD_TESTS=OFF -DMPDRIG_BUILD_BENCHMARKS=OFF
fi
mkdir -p "$root/out"

pids=()
stop() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  pids=()
}
trap 'echo; echo "deploy/demo.sh: stopping"; stop; exit 130' INT TERM
trap stop EXIT

# The controller measures the last 20 s (or less in a short run) of BHP swing on both rigs.
window=20
if awk -v d="$duration" 'BEGIN { exit !(d > 0 && d < 40) }'; then
  window="$(awk -v d="$duration" 'BEGIN { print d / 2 }')"
fi
[[ "$duration" == 0 ]] && window=0
measure=(--duration "$duration" --measure-last "$window")

"$build/clients/rig_echo" --rig rig-1 --domain "$domain" --out "$root/out/demo.csv" \
  2>/dev/null &
pids+=($!)
echo_pid=$!
"$build/tools/mpdrig" serve --clock realtime --rate-hz 100 --domain "$domain" \
  --rig rig-1 --rig rig-2 --heave-amp-m 0.1 --heave-hz 0.2 --pump-lpm 5 --choke-deg 31 \
  --duration "$duration" &
pids+=($!)
serve_pid=$!
summary="$(mktemp)"
"$build/clients/bhp_controller" --rig rig-1 --domain "$domain" --use-estimate "${measure[@]}" \
  >>"$summary" 2>/dev/null &
pids+=($!)
"$build/clients/bhp_controller" --rig rig-2 --domain "$domain" --open-loop "${measure[@]}" \
  >>"$summary" 2>/dev/null &
pids+=($!)
# The shadow model beside rig-1 and the dashboard; they stop with the service (or at the end).
"$build/tools/mpdrig" shadow --rig rig-1 --domain "$domain" --duration "$duration" \
  >/dev/null 2>&1 &
pids+=($!)
shadow_pid=$!
dashboard_log="$(mktemp)"
"$build/clients/dashboard" --domain "$domain" --port "$port" --duration "$duration" \
  >"$dashboard_log" 2>&1 &
pids+=($!)
dashboard_pid=$!
for _ in $(seq 50); do  # its address once it listens (or why it could not)
  grep -q 'http://' "$dashboard_log" 2>/dev/null && break
  kill -0 "$dashboard_pid" 2>/dev/null || break
  sleep 0.1
done
dashboard_url="$(grep -o 'http://[^ ]*' "$dashboard_log" || true)"

cat <<EOF

The virtual rig runs for ${duration} s of real time (0: until Ctrl-C). In another terminal:
  $build/clients/rig_echo --rig rig-1 --domain $domain --samples 500 --out -     # rig-1's sensors
  $build/clients/rig_echo --rig rig-2 --domain $domain --samples 500 --out -     # the uncontrolled rig
  $build/clients/bhp_controller --help      # how the controller works
  $build/tools/mpdrig serve --help        # topics: sensors, estimate, pressure profile, status
rig-1's choke is controlled (bhp_controller, on the observer's BHP estimate; it watches 20 s first),
rig-2's stays at 31 deg. Ctrl-C stops everything.

EOF
if [[ -n "$dashboard_url" ]]; then
  echo "Live dashboard: open $dashboard_url in a browser (the rigs, the observer, the shadow model)."
else
  echo "The dashboard did not start: $(cat "$dashboard_log")"
fi
echo
wait "$serve_pid" || true
# The service has stopped: the recorder stops on SIGTERM (it writes what it has), and so do the
# shadow and the dashboard; the controllers stop after their last sample.
kill "$echo_pid" "$shadow_pid" "$dashboard_pid" 2>/dev/null || true
for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
pids=()
if [[ -s "$summary" ]]; then
  echo "bottom-hole pressure PT1 over the last ${window} s: the heave's swing (RMS of PT1's periodic"
  echo "part, the sensors' noise left out) and half peak-to-peak (the noise alone reads about 0.07 bar):"
  while read -r line; do
    get() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<"$line"; }
    rig="$(sed -n 's/^rig=\([^ ]*\) .*/\1/p' <<<"$line")"
    printf '  %s (%s): %s bar RMS, %s bar half peak-to-peak\n' "$rig" "$(get mode)" \
      "$(get PT1_periodic_rms_bar)" "$(get PT1_amplitude_bar)"
  done <"$summary"
fi
rm -f "$summary" "$dashboard_log"
[[ -s "$root/out/demo.csv" ]] && echo "rig-1 recorded as a rig log: $root/out/demo.csv (mpdrig compare reads it)"
echo "offline, without DDS: $build/tools/mpdrig demo"
