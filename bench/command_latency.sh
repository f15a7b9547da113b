#!/usr/bin/env bash
# Command-to-sensor latency of the virtual rig, and ddsperf's ping-pong round trip in the same
# run on the same loopback DDS domain, for scale. The rig runs in real time at RATE_HZ (default
# 1 kHz); mpdrig_command_latency toggles the pump and times each command until the first sensor
# sample whose FT2 shows it. Target: latency <= one sensor period + 2 x ddsperf's round trip.
#
#   bash bench/command_latency.sh            # 2000 commands, about 25 s
#   COUNT=5000 RATE_HZ=500 bash bench/command_latency.sh
#   SECURITY=1 bash bench/command_latency.sh  # the same with DDS Security (a class made by
#                                             # deploy/security/make-class, student rig-1)
#   bash bench/security_cost.sh               # both, one after the other
#
# Environment: BUILD_DIR (default <repo>/build, with -DMPDRIG_BUILD_BENCHMARKS=ON),
# DOMAIN (default 78), COUNT (default 2000), RATE_HZ (default 1000), SECURITY (default 0).
# With SECURITY=1 the service and the probe authenticate, are access-controlled and encrypt
# (governance: discovery, liveliness, metadata and payload ENCRYPT); ddsperf stays unsecured
# (its own topics; it gives the plain round trip for scale in both runs).
# Note: ddsperf prints half the round trip (its source: (now - source timestamp) / 2); the
# round trip below is twice its figures.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$repo/build}"
mpdrig="$build/tools/mpdrig"
probe="$build/bench/mpdrig_command_latency"
for exe in "$mpdrig" "$probe"; do
  [[ -x "$exe" ]] || { echo "error: $exe not built (deploy/build.sh -DMPDRIG_BUILD_BENCHMARKS=ON)" >&2; exit 1; }
done
command -v ddsperf >/dev/null || { echo "error: ddsperf not found (apt-get install cyclonedds-tools)" >&2; exit 1; }
domain="${DOMAIN:-78}"
count="${COUNT:-2000}"
rate="${RATE_HZ:-1000}"
# The commands come 5-15 ms apart: about 10 ms each, plus discovery.
seconds=$(( count / 100 + 10 ))

# ddsperf speaks the same loopback-only configuration as mpdrig (dds::LoopbackConfig()).
export CYCLONEDDS_URI='<General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>40</MaxAutoParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery>'
work="$(mktemp -d)"
pids=()
cleanup() { for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$work"; }
trap cleanup EXIT INT TERM

serve_security=()
probe_security=()
if [[ "${SECURITY:-0}" == 1 ]]; then
  "$repo/deploy/security/make-class" "$work/class" rig-1 >/dev/null
  serve_security=(--security "$work/class/service")
  probe_security=(--security "$work/class/rig-1")
  echo "DDS Security on (make-class: service and student rig-1; partition rig.rig-1)"
else
  echo "DDS Security off"
fi
# Noise-free sensors: the probe recognises a command by FT2 reading exactly the commanded flow
# (with serve's default lab noise it never does, and the probe gives up).
"$mpdrig" serve --clock realtime --rate-hz "$rate" --duration "$seconds" --domain "$domain" \
  --sensor-noise none "${serve_security[@]}" 2>"$work/serve.txt" &
pids+=($!)
ddsperf -i "$domain" -D "$seconds" pong >/dev/null 2>&1 &
pids+=($!)
sleep 0.5
ddsperf -i "$domain" -D $(( seconds - 3 )) ping 1kHz >"$work/ping.txt" 2>&1 &
pids+=($!)
latency="$("$probe" --domain "$domain" --count "$count" "${probe_security[@]}")"
wait "${pids[2]}" 2>/dev/null || true
kill -INT "${pids[0]}" 2>/dev/null || true  # the service prints its deadline misses on the way out
wait "${pids[0]}" 2>/dev/null || true

echo "$latency"
# Per-second lines: "... 50% 26.929us 90% 30.520us 99% 35.097us ...": half round trips.
awk -v tick_ms="$(awk -v r="$rate" 'BEGIN { print 1000 / r }')" -v latency="$latency" '
  / 50% / {
    for (i = 1; i <= NF; ++i) {
      if ($i == "50%") p50[n] = $(i + 1) + 0
      if ($i == "99%") p99[n] = $(i + 1) + 0
    }
    ++n
  }
  function median(a, k,   i, j, t) {
    for (i = 0; i < k; ++i) for (j = i + 1; j < k; ++j) if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
    return a[int(k / 2)]
  }
  END {
    if (n == 0) { print "ddsperf: no round trips measured"; exit 1 }
    rtt50 = 2 * median(p50, n) / 1000; rtt99 = 2 * median(p99, n) / 1000
    printf "ddsperf ping 1kHz / pong, %d s: round trip p50 %.3f ms, p99 %.3f ms (median of the per-second figures, x2)\n", n, rtt50, rtt99
    split(latency, w, " ")
    for (i in w) { if (w[i] == "p50") l50 = w[i + 1] + 0; if (w[i] == "p99") l99 = w[i + 1] + 0 }
    t50 = tick_ms + 2 * rtt50; t99 = tick_ms + 2 * rtt99
    printf "target one tick (%.3f ms) + 2 x round trip: %.3f ms (p50 RTT), %.3f ms (p99 RTT)\n", tick_ms, t50, t99
    printf "latency p50 %.3f ms: %s;  p99 %.3f ms: %s\n", l50, (l50 <= t50 ? "meets" : "misses"), l99, (l99 <= t99 ? "meets" : "misses")
  }' "$work/ping.txt"
grep -h "deadline\|refused" "$work/serve.txt" || true
echo "load average (1/5/15 min) during the run: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
