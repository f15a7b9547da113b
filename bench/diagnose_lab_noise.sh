#!/usr/bin/env bash
# diagnose at the lab's noise, as a user runs it: for each hidden effect (or `none`) and seed,
# `mpdrig synth` writes a 120 s, 100 Hz log with Table 4.1.1's noise on every channel, `mpdrig
# diagnose` names what it finds, and one line per log says the verdict, whether the hidden effect
# was ranked first and named, and the error before and after. A summary per effect follows.
#
#   bash bench/diagnose_lab_noise.sh "none:1-20" "helical_friction:1-10" ...
#
# Each argument is EFFECT:FIRST-LAST. Environment: BUILD_DIR (default <repo>/build), WORK_DIR
# (default a temp dir), NOISE (synth's --sensor-noise, default lab), JOBS (logs diagnosed at once,
# default 1; diagnose itself uses every core).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mpdrig="${BUILD_DIR:-${repo}/build}/tools/mpdrig"
work="${WORK_DIR:-$(mktemp -d)}"
noise="${NOISE:-lab}"
jobs="${JOBS:-1}"
[[ -x "${mpdrig}" ]] || { echo "error: ${mpdrig} not built (./deploy/build.sh)" >&2; exit 1; }
[[ $# -gt 0 ]] || { sed -n 2,12p "$0"; exit 2; }

one() {
  local effect="$1" seed="$2"
  local log="${work}/${effect}_${seed}.csv" json="${work}/${effect}_${seed}.json"
  "${mpdrig}" synth --effect "${effect}" --seed "${seed}" --duration 120 --rate-hz 100 \
    --sensor-noise "${noise}" --out "${log}" 2>/dev/null
  "${mpdrig}" diagnose "${log}" --json "${json}" --quiet >/dev/null 2>"${work}/${effect}_${seed}.err" ||
    echo "diagnose failed: ${effect} ${seed}" >&2
}
export -f one
export mpdrig work noise

cases=()
for arg in "$@"; do
  effect="${arg%%:*}" range="${arg#*:}"
  for ((s = ${range%-*}; s <= ${range#*-}; s++)); do cases+=("${effect} ${s}"); done
done
printf '%s\n' "${cases[@]}" | xargs -P "${jobs}" -L 1 bash -c 'one "$0" "$1"'

python3 - "${work}" "${cases[@]}" <<'PY'
import json, sys, collections
work, cases = sys.argv[1], sys.argv[2:]
rows = collections.defaultdict(list)
print(f"{'effect':22} {'seed':>4}  {'verdict':22} first named  error% before -> after   top gain%")
for case in cases:
    effect, seed = case.split()
    try:
        d = json.load(open(f"{work}/{effect}_{seed}.json"))
    except Exception as e:
        print(f"{effect:22} {seed:>4}  (no result: {e})"); continue
    verdict = d.get("verdict") or "-"
    cands = d.get("candidates", [])
    first = cands[0]["effect"] if cands else "-"
    equivalent = d.get("equivalent", []) or []
    named = effect != "none" and (verdict == effect or effect in equivalent)
    base = d["baseline"]["error"]
    after = cands[0]["error"] if cands else base
    gain = 100.0 * (1.0 - cands[0]["penalised_error"] / base) if cands else 0.0
    wrong = verdict != "-" and not named
    rows[effect].append((first == effect, named, wrong, verdict != "-"))
    print(f"{effect:22} {seed:>4}  {verdict:22} {('yes' if first == effect else first)[:5]:>5} "
          f"{'yes' if named else 'no':>5}  {100*base:6.2f} -> {100*after:6.2f}   {first} {gain:.1f}")
print()
print(f"{'effect':22} {'logs':>4} {'ranked first':>12} {'named':>6} {'wrong verdicts':>14} {'any verdict':>11}")
for effect, r in rows.items():
    n = len(r)
    print(f"{effect:22} {n:4d} {sum(x[0] for x in r):12d} {sum(x[1] for x in r):6d} "
          f"{sum(x[2] for x in r):14d} {sum(x[3] for x in r):11d}")
PY
