#!/usr/bin/env bash
# Which catalogue effect, or pair of effects, explains the rig's three first resonances (thesis 9.1,
# 11.1: choke closed 0.44 Hz, open 0.25 Hz, closed by a valve after the copper pipe 0.49 Hz) with
# the wave speed held at the fronts' 1173 m/s (8.3.2): `mpdrig fit --resonances` per candidate,
# one line each with the fitted parameters, the model's three resonances and the largest error.
#
#   bash bench/resonance_effects.sh [RESONANCES.csv]
#
# Environment: BUILD_DIR (default <repo>/build), WAVE_SPEED (default 1173), CELLS (the simulated
# response's grid for effects the analytic one does not hold, default 60), MODEL (default linear).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mpdrig="${BUILD_DIR:-${repo}/build}/tools/mpdrig"
resonances="${1:-${repo}/docs/examples/thesis-resonances.csv}"
c="${WAVE_SPEED:-1173}"
[[ -x "${mpdrig}" ]] || { echo "error: ${mpdrig} not built (./deploy/build.sh)" >&2; exit 1; }

candidates=(
  "none"
  "topside_compliance" "hose_compliance" "gas_entrainment" "piston_compressibility"
  "unsteady_friction" "helical_friction" "choke_inertia" "sensor_lag"
  "topside_compliance+gas_entrainment" "topside_compliance+hose_compliance"
  "topside_compliance+piston_compressibility" "hose_compliance+gas_entrainment"
)
summarise="$(cat <<'PY'
import json, sys
fit = json.load(sys.stdin)
by = {c["configuration"]: c for c in fit["configurations"]}
def hz(name):
    return f'{by[name]["model_hz"]:.4f}' if name in by else "-"
params = ", ".join(f'{k}={v["estimate"]:.3g}' for k, v in fit["params"].items())
methods = sorted({c["response"] for c in fit["configurations"]})
print(f'{sys.argv[1]:<42} {hz("choke-closed"):<8} {hz("choke-open"):<8} '
      f'{hz("closed-at-pipe-end"):<8} {fit["max_error_hz"]:<9.4f} {fit["chi2_after"]:<7.3g} '
      f'{params or "-"} ({"/".join(methods)})')
PY
)"
printf '%-42s %-8s %-8s %-8s %-9s %-7s %s\n' "effects (c = ${c} m/s held)" closed open valve max_err chi2 \
  "fitted (response)"
for candidate in "${candidates[@]}"; do
  effects=()
  if [[ "${candidate}" != none ]]; then
    IFS=+ read -ra names <<<"${candidate}"
    for name in "${names[@]}"; do effects+=(--effect "${name}"); done
  fi
  json="$("${mpdrig}" fit --resonances "${resonances}" --set "wave_speed_mps=${c}" \
    --hold wave_speed_mps "${effects[@]}" --model "${MODEL:-linear}" --cells "${CELLS:-60}" \
    --quiet --json - 2>&1)" || { printf '%-42s failed: %s\n' "${candidate}" "${json}"; continue; }
  python3 -c "${summarise}" "${candidate}" <<<"${json}"
done
