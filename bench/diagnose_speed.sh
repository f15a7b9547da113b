#!/usr/bin/env bash
# diagnose's speed target: `mpdrig diagnose` on a 120 s, 100 Hz log in <= 30 s on the 2-core
# machine. Makes synthetic logs with a hidden effect (and one without), diagnoses each under
# /usr/bin/time and prints wall time, CPU time, peak RSS, model runs and the verdict.
#
#   bash bench/diagnose_speed.sh [effect ...]      (default: choke_inertia none)
#
# Environment: BUILD_DIR (default <repo>/build), WORK_DIR (default a temp dir), SEED (default 1).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mpdrig="${BUILD_DIR:-${repo}/build}/tools/mpdrig"
work="${WORK_DIR:-$(mktemp -d)}"
seed="${SEED:-1}"
effects=("$@")
[[ ${#effects[@]} -eq 0 ]] && effects=(choke_inertia none)
[[ -x "${mpdrig}" ]] || { echo "error: ${mpdrig} not built (./deploy/build.sh)" >&2; exit 1; }

printf '%-22s %8s %8s %8s %7s  %s\n' effect wall_s cpu_s rss_mb runs verdict
for effect in "${effects[@]}"; do
  log="${work}/${effect}_${seed}.csv"
  "${mpdrig}" synth --effect "${effect}" --seed "${seed}" --duration 120 --rate-hz 100 \
    --out "${log}" 2>/dev/null
  /usr/bin/time -f '%e %U %S %M' -o "${work}/time" \
    "${mpdrig}" diagnose "${log}" --json "${work}/${effect}.json" --quiet >"${work}/summary"
  read -r wall user sys rss <"${work}/time"
  runs="$(sed -n 's/.*(\([0-9]*\) model runs.*/\1/p' "${work}/summary")"
  verdict="$(sed -n 's/^verdict: \([^ ;]*\).*/\1/p' "${work}/summary")"
  awk -v e="${effect}" -v w="${wall}" -v u="${user}" -v s="${sys}" -v r="${rss}" \
    -v n="${runs}" -v v="${verdict}" 'BEGIN { printf "%-22s %8.1f %8.1f %8.0f %7s  %s\n", e, w, u + s, r / 1024, n, v }'
done
