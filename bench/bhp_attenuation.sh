#!/usr/bin/env bash
# How much bhp_controller attenuates the heave-induced bottom-hole pressure oscillation compared
# with a fixed choke. One `mpdrig serve --clock lockstep` runs one rig per mode under the same
# heave; one bhp_controller per rig steps it (deterministic: the numbers do not depend on the
# machine's load). Loopback DDS only.
#
#   bash bench/bhp_attenuation.sh                  # 0.1 m at 0.1, 0.15 and 0.2 Hz, 5 L/min, 31 deg
#   FREQS="0.2" PUMP_LPM=20 CHOKE_DEG=45 bash bench/bhp_attenuation.sh
#
# Environment: BUILD_DIR (default <repo>/build, must hold tools/mpdrig and clients/),
# DOMAIN (DDS domain, default 77), DURATION (rig time per run [s], default 120),
# MEASURE_LAST (the window measured [s], default 40), AMP_M (heave amplitude, default 0.1),
# SENSOR_NOISE (serve's --sensor-noise, default lab: thesis Table 4.1.1; none: noise-free).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$repo/build}"
mpdrig="$build/tools/mpdrig"
controller="$build/clients/bhp_controller"
for exe in "$mpdrig" "$controller"; do
  [[ -x "$exe" ]] || { echo "error: $exe not built (deploy/build.sh)" >&2; exit 1; }
done
domain="${DOMAIN:-77}"
duration="${DURATION:-120}"
window="${MEASURE_LAST:-40}"
amp="${AMP_M:-0.1}"
pump="${PUMP_LPM:-5}"
choke="${CHOKE_DEG:-31}"
freqs="${FREQS:-0.1 0.15 0.2}"
noise="${SENSOR_NOISE:-lab}"

serve_pid=""
cleanup() { [[ -n "$serve_pid" ]] && kill "$serve_pid" 2>/dev/null && wait "$serve_pid" 2>/dev/null; true; }
trap cleanup EXIT INT TERM

printf '%-6s %-16s %10s %12s %10s %12s %9s %s\n' "f [Hz]" "mode" "p2p/2 [bar]" "periodic rms" "vs fixed" "at f [bar]" "mean" "choke range [deg]"
for f in $freqs; do
  "$mpdrig" serve --clock lockstep --rate-hz 100 --heave-amp-m "$amp" --heave-hz "$f" \
    --pump-lpm "$pump" --choke-deg "$choke" --domain "$domain" --sensor-noise "$noise" \
    --rig fixed --rig pi --rig pi-ff --rig pi-ff-est 2>/dev/null &
  serve_pid=$!
  common=(--lockstep --domain "$domain" --duration "$duration" --measure-last "$window" --timeout 60)
  out="$(
    exec 2>/dev/null
    "$controller" "${common[@]}" --rig fixed --open-loop &
    "$controller" "${common[@]}" --rig pi --no-feedforward &
    "$controller" "${common[@]}" --rig pi-ff &
    "$controller" "${common[@]}" --rig pi-ff-est --use-estimate &
    wait
  )"
  kill "$serve_pid"; wait "$serve_pid" 2>/dev/null || true; serve_pid=""
  fixed_rms="$(sed -n 's/^rig=fixed .*PT1_periodic_rms_bar=\([^ ]*\).*/\1/p' <<<"$out")"
  for rig in fixed pi pi-ff pi-ff-est; do
    line="$(grep "^rig=$rig " <<<"$out")"
    get() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<"$line"; }
    printf '%-6s %-16s %10s %12s %10s %12s %9s %s..%s\n' "$f" "$(get mode)" \
      "$(get PT1_amplitude_bar)" "$(get PT1_periodic_rms_bar)" \
      "$(awk -v a="$fixed_rms" -v b="$(get PT1_periodic_rms_bar)" 'BEGIN{printf "%.1fx", a/b}')" \
      "$(get PT1_heave_bar)" "$(get PT1_mean_barg)" "$(get choke_min_deg)" "$(get choke_max_deg)"
  done
done
echo "(${amp} m heave, ${pump} L/min through a ${choke} deg choke, sensor noise ${noise}; PT1 over the last ${window} s of ${duration} s: half peak-to-peak, the RMS of its periodic part (harmonics 1-3 of the heave, least squares; the noise is not in it) and the ratio of that to the fixed choke's, the amplitude at the heave frequency, the mean; lockstep, 100 Hz)"
