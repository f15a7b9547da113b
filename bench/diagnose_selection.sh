#!/usr/bin/env bash
# diagnose's forward selection over many seeds, as a user runs it: for each set of hidden effects
# and seed, `mpdrig synth` writes a log at the lab's noise with those effects (strengths drawn as
# synth draws them, or given), `mpdrig diagnose` selects, and one line per log says what was
# selected, whether every hidden effect was, any false one, and the error step by step. A summary
# per set follows.
#
#   bash bench/diagnose_selection.sh "sensor_lag+unsteady_friction:1-10" "none:1-10" ...
#   bash bench/diagnose_selection.sh "sensor_lag:time_constant_s=0.1+unsteady_friction:k=0.06:1-5"
#
# Each argument is EFFECTS:FIRST-LAST, EFFECTS one or more --effect specs joined by '+', or none.
# Environment: BUILD_DIR (default <repo>/build), WORK_DIR (default a temp dir), DURATION (s,
# default 40), RATE (Hz, default 50), NOISE (synth's --sensor-noise, default lab).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mpdrig="${BUILD_DIR:-${repo}/build}/tools/mpdrig"
work="${WORK_DIR:-$(mktemp -d)}"
duration="${DURATION:-40}"
rate="${RATE:-50}"
noise="${NOISE:-lab}"
[[ -x "${mpdrig}" ]] || { echo "error: ${mpdrig} not built (./deploy/build.sh)" >&2; exit 1; }
[[ $# -gt 0 ]] || { sed -n 2,14p "$0"; exit 2; }

cases=()
for arg in "$@"; do
  effects="${arg%:*}" range="${arg##*:}"
  for ((s = ${range%-*}; s <= ${range#*-}; s++)); do
    name="$(echo "${effects}" | tr '+:=,' '_._.')_${s}"
    flags=()
    IFS='+' read -r -a specs <<<"${effects}"
    for spec in "${specs[@]}"; do flags+=(--effect "${spec}"); done
    "${mpdrig}" synth "${flags[@]}" --seed "${s}" --duration "${duration}" --rate-hz "${rate}" \
      --sensor-noise "${noise}" --out "${work}/${name}.csv" 2>/dev/null
    /usr/bin/time -f '%e' -o "${work}/${name}.time" "${mpdrig}" diagnose "${work}/${name}.csv" \
      --json "${work}/${name}.json" --quiet >/dev/null 2>"${work}/${name}.err" ||
      echo "diagnose failed: ${effects} ${s}" >&2
    cases+=("${effects} ${s} ${name}")
  done
done

python3 - "${work}" "${cases[@]}" <<'PY'
import json, sys, collections
work, cases = sys.argv[1], sys.argv[2:]
rows = collections.defaultdict(list)
print(f"{'hidden':40} {'seed':>4}  {'selected':40} all  false  wall_s  error% step by step")
for case in cases:
    effects, seed, name = case.split()
    hidden = [] if effects == "none" else [e.split(":")[0] for e in effects.split("+")]
    try:
        d = json.load(open(f"{work}/{name}.json"))
        wall = float(open(f"{work}/{name}.time").read().split()[-1])
    except Exception as e:
        print(f"{effects:40} {seed:>4}  (no result: {e})"); continue
    selected = [s["effect"] for s in d.get("selected", [])]
    equivalent = d.get("equivalent", []) or []
    # A hidden effect counts as named where it is selected, or named `equivalent` to the first.
    named = all(h in selected or h in equivalent for h in hidden)
    # Not false: the verdict where a hidden effect is named `equivalent` to it (the two inlet
    # compliances tie where the log does not excite the compartment's own mode).
    false = [s for i, s in enumerate(selected)
             if s not in hidden and not (i == 0 and any(h in equivalent for h in hidden))]
    steps = " -> ".join([f"{100*d['baseline']['error']:.2f}"] +
                        [f"{100*s['error']:.2f}" for s in d.get("selected", [])])
    nxt = d.get("next")
    rows[effects].append((named, len(false), wall, bool(selected)))
    print(f"{effects[:40]:40} {seed:>4}  {'+'.join(selected) or '-':40} {'yes' if named else 'no':>3} "
          f"{len(false):5d} {wall:7.1f}  {steps}"
          + (f"  (next {nxt['effect']} {100*nxt['improvement']:.1f}%)" if nxt else ""))
print()
print(f"{'hidden':40} {'logs':>4} {'all named':>9} {'false effects':>13} {'any selected':>12} {'wall s':>12}")
for effects, r in rows.items():
    walls = [x[2] for x in r]
    print(f"{effects[:40]:40} {len(r):4d} {sum(x[0] for x in r):9d} {sum(x[1] for x in r):13d} "
          f"{sum(x[3] for x in r):12d} {min(walls):5.1f}-{max(walls):5.1f}")
PY
