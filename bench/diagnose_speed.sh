#!/usr/bin/env bash
# diagnose's speed (issue 25): `mpdrig diagnose` on a 120 s, 100 Hz log at the lab's noise, with
# forward selection, against `mpdrig simulate --inputs` of the same log (both at diagnose's 50
# cells): the wall time in replays' worth. Makes synthetic logs with a hidden effect (and one
# without), diagnoses each and prints wall time, CPU time, peak RSS, model runs and the verdict,
# then per log the wall time and model runs of each stage (the baseline; round 1, the catalogue
# screened against it, and its polishing; the verdict's comparison; each later selection round
# and its polishing) and each parallel task's own time. Model runs are deterministic (the same log, the same count); wall times on a
# shared machine are not: repeat them (REPEAT).
#
#   bash bench/diagnose_speed.sh [effect ...]      (default: choke_inertia none)
#
# Environment: BUILD_DIR (default <repo>/build), MPDRIG (a binary to measure instead, e.g. an
# older build), WORK_DIR (default a temp dir), SEED (default 1), DURATION (s, default 120), RATE
# (Hz, default 100), REPEAT (diagnoses per log, default 1: the best wall time is kept).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mpdrig="${MPDRIG:-${BUILD_DIR:-${repo}/build}/tools/mpdrig}"
work="${WORK_DIR:-$(mktemp -d)}"
seed="${SEED:-1}"
duration="${DURATION:-120}"
rate="${RATE:-100}"
repeat="${REPEAT:-1}"
effects=("$@")
[[ ${#effects[@]} -eq 0 ]] && effects=(choke_inertia none)
[[ -x "${mpdrig}" ]] || { echo "error: ${mpdrig} not built (./deploy/build.sh)" >&2; exit 1; }

for effect in "${effects[@]}"; do
  "${mpdrig}" synth --effect "${effect}" --seed "${seed}" --duration "${duration}" \
    --rate-hz "${rate}" --out "${work}/${effect}_${seed}.csv" 2>/dev/null
done

python3 - "${mpdrig}" "${work}" "${seed}" "${repeat}" "${effects[@]}" <<'PY'
import json, resource, subprocess, sys, time
mpdrig, work, seed, repeat, effects = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5:]

def timed(args):
    """Runs args; returns wall s, CPU s, peak RSS (MB) and, for diagnose, the wall time at which
    each of its progress stages began (stderr lines 'diagnose: NN% STAGE') and each parallel
    task's own wall time ('diagnose: KIND done in S s (K of N)'), in the order they ended."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    stages = []
    tasks = []
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    for line in proc.stderr:
        parts = line.split()
        if len(parts) == 3 and parts[0] == "diagnose:" and parts[1].endswith("%"):
            if not stages or stages[-1][0] != parts[2]:
                stages.append((parts[2], time.monotonic() - start))
        if parts[:1] == ["diagnose:"] and " done in " in line:
            kind, rest = line[len("diagnose: "):].split(" done in ", 1)
            tasks.append((stages[-1][0] if stages else "", kind, float(rest.split()[0])))
    if proc.wait() != 0:
        sys.exit(f"failed: {' '.join(args)}")
    wall = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return wall, cpu, after.ru_maxrss / 1024, stages, tasks

print(f"{'log':22} {'wall_s':>7} {'cpu_s':>7} {'rss_mb':>6} {'runs':>6} {'sim_s':>6} "
      f"{'replays':>7}  verdict / selected")
details = []
for effect in effects:
    log = f"{work}/{effect}_{seed}.csv"
    sim = min(timed([mpdrig, "simulate", "--inputs", log, "--cells", "50",
                     "--out", f"{work}/sim.csv"])[0] for _ in range(3))
    best = None
    for _ in range(repeat):
        result = timed([mpdrig, "diagnose", log, "--json", f"{work}/{effect}.json"])
        if best is None or result[0] < best[0]:
            best = result
    wall, cpu, rss, stages, tasks = best
    d = json.load(open(f"{work}/{effect}.json"))
    selected = "+".join(s["effect"] for s in d.get("selected", [])) or "-"
    print(f"{effect + '_' + seed:22} {wall:7.1f} {cpu:7.1f} {rss:6.0f} {d['replays']:6d} {sim:6.2f} "
          f"{wall / sim:7.1f}  {d['verdict'] or 'none'} / {selected}")
    details.append((effect, wall, stages, d.get("runs", []), tasks))

for effect, wall, stages, runs, tasks in details:
    print(f"\n{effect}_{seed}: wall s per progress stage (diagnose's stderr)")
    for i, (name, t0) in enumerate(stages):
        t1 = stages[i + 1][1] if i + 1 < len(stages) else wall
        print(f"  {name:12} {t0:7.2f} .. {t1:7.2f}  {t1 - t0:7.2f}")
    if tasks:
        print(f"{effect}_{seed}: parallel tasks, s each (two cores share them; the longest sets "
              f"a stage's tail)")
        for stage, kind, seconds in tasks:
            print(f"  {stage:12} {kind:36} {seconds:6.1f}")
    if not runs:
        continue
    print(f"{effect}_{seed}: model runs per stage (JSON 'runs')")
    print(f"  {'stage':16} {'scans':>6} {'fits':>6} {'detect':>6} {'score':>6} {'total':>6}")
    total = {"scans": 0, "fits": 0, "detectability": 0, "scoring": 0}
    for r in runs:
        n = sum(r[k] for k in total)
        for k in total:
            total[k] += r[k]
        print(f"  {r['stage']:16} {r['scans']:6d} {r['fits']:6d} {r['detectability']:6d} "
              f"{r['scoring']:6d} {n:6d}")
    print(f"  {'all':16} {total['scans']:6d} {total['fits']:6d} {total['detectability']:6d} "
          f"{total['scoring']:6d} {sum(total.values()):6d}")
PY
