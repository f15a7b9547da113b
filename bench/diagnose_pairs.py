#!/usr/bin/env python3
"""diagnose on logs with two hidden effects, every pair of the catalogue, as the several-effects
issue's done-when measures it: for each pair and seed `mpdrig synth` writes a log at the lab's
noise (the excitation rotates through the lab's sines and sweep, an irregular sea, a pump stop and
a choke closure), `mpdrig diagnose` selects, and a line per log says what was selected, whether
both hidden effects were named (selected, or `equivalent` to the verdict), any effect named that
is not there (the two inlet compliances name each other: one lumped V/K in the heave band), and
how visible each hidden effect is beyond its partner.

Visibility of B beyond A: the model with both effects against the model with A alone, both
replaying the noise-free log's own inputs (`mpdrig simulate --inputs`, the log's base parameters
and strengths, synth's 50 cells), their RMS difference on the output channel where it is largest,
in units of that channel's noise RMS (the noisy log against its own noise-free twin); without
column_separation the replay may go below zero absolute (--allow-negative-pressure). A pair
counts toward the done-when where both are visible at >= --visible. (Not synth's log with A alone:
synth chooses a low-pressure operating point for logs with column_separation, so A alone would be
another experiment, and a cavity that never opens in the log would count as visible.)

  python3 bench/diagnose_pairs.py --seeds 1-1 --jobs 1
  python3 bench/diagnose_pairs.py --pairs sensor_lag+unsteady_friction,choke_inertia+pump_curve --seeds 1-3

The two inlet closures (piston_compressibility, hose_compliance) and the two outlet closures
(choke_inertia, topside_compliance) cannot be in one model and are not paired. Logs, JSON and a table (pairs.txt) go to --work (default a temp dir).
"""
import argparse
import concurrent.futures
import csv
import itertools
import json
import math
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import time

CATALOGUE = ["unsteady_friction", "helical_friction", "choke_inertia", "piston_compressibility",
             "hose_compliance", "topside_compliance", "sensor_lag", "gas_entrainment",
             "column_separation", "pump_curve"]
# Each pair closes the same pipe end (closes_inlet / closes_outlet): the model holds one of them.
EXCLUSIVE = [{"piston_compressibility", "hose_compliance"}, {"choke_inertia", "topside_compliance"}]
INLET_COMPLIANCES = {"piston_compressibility", "hose_compliance"}
INPUTS = {"time_s", "piston_position_m", "choke_position_deg", "FT2_lpm"}


def excitation(index, duration):
    """The index-th excitation of the rotation, as synth flags, and its name."""
    kind = index % 4
    if kind == 0:
        return "lab", []
    if kind == 1:
        return "sea", ["--heave", "sea"]
    if kind == 2:
        start, length = 0.4 * duration, 0.2 * duration
        return "pump-stop", ["--pump-stop", f"{start:g}:{length:g}"]
    start, length = 0.6 * duration, 0.15 * duration
    return "choke-close", ["--choke-close", f"{start:g}:{length:g}"]


def read_log(path):
    rows = [r for r in csv.reader(l for l in open(path) if not l.startswith("#"))]
    header, data = rows[0], rows[1:]
    columns = {name: [float(r[i]) for r in data] for i, name in enumerate(header)}
    return columns


def rms(values):
    return math.sqrt(sum(v * v for v in values) / max(1, len(values)))


def hidden_specs(log_path):
    """The `# hidden:` metadata line as synth --effect specs with every strength given."""
    for line in open(log_path):
        if line.startswith("# hidden:"):
            text = line.split(":", 1)[1].split(";")[0]
            specs = []
            for part in text.split(" + "):
                words = part.split()
                specs.append(words[0] + (":" + ",".join(words[1:]) if len(words) > 1 else ""))
            return specs
    raise RuntimeError(f"{log_path}: no '# hidden:' line")


def base_settings(log_path):
    """The `# hidden:` line's base parameters as simulate --set flags."""
    for line in open(log_path):
        if line.startswith("# hidden:"):
            m = re.search(r"wave speed ([0-9.eE+-]+) m/s, f1 ([0-9.eE+-]+) 1/s, "
                          r"choke leak ([0-9.eE+-]+) m\^2", line)
            if not m:
                raise RuntimeError(f"{log_path}: no base parameters in '# hidden:'")
            return ["--set", f"wave_speed_mps={m.group(1)}", "--set",
                    f"friction_f1_per_s={m.group(2)}", "--set", f"choke_leak_m2={m.group(3)}"]
    raise RuntimeError(f"{log_path}: no '# hidden:' line")


def below_detectability(d, effect, spec):
    """True where the diagnosis's last estimate of `effect`'s detectability lies beyond the
    strength `spec` (NAME:key=value) hides, False where within it, None where not known."""
    entry = None
    rounds = d.get("later_rounds") or []
    for candidate in (rounds[-1]["candidates"] if rounds else []):
        if candidate["effect"] == effect:
            entry = candidate
    if entry is None and d.get("next") and d["next"]["effect"] == effect:
        entry = d["next"]
    if entry is None:
        entry = next((c for c in d.get("candidates", []) if c["effect"] == effect), None)
    if entry is None or "strength_key" not in entry or ":" not in spec:
        return None
    key = entry["strength_key"].split(".", 1)[1]
    values = dict(kv.split("=") for kv in spec.split(":", 1)[1].split(","))
    if key not in values:
        return None
    hidden = float(values[key])
    threshold = entry.get("detectable_from")
    if threshold is None:  # not detectable at this noise even at the scan's limit
        return True
    return hidden > threshold if entry.get("strength_inverse") else hidden < threshold


def run_case(mpdrig, work, pair, seed, index, duration, rate, reuse, keep_logs):
    name = f"{pair[0]}+{pair[1]}_{seed}"
    exc_name, exc_flags = excitation(index, duration)
    common = ["--seed", str(seed), "--duration", str(duration), "--rate-hz", str(rate)] + exc_flags
    noisy, truth = work / f"{name}.csv", work / f"{name}_truth.csv"
    json_path, time_path = work / f"{name}.json", work / f"{name}.time"
    done = reuse and json_path.exists() and time_path.exists()
    have_logs = keep_logs and noisy.exists() and truth.exists()
    if not done and not have_logs:
        subprocess.run([mpdrig, "synth", "--effect", pair[0], "--effect", pair[1], *common,
                        "--sensor-noise", "lab", "--out", noisy, "--truth-out", truth],
                       check=True, capture_output=True, text=True)
    specs = hidden_specs(noisy)
    base = base_settings(noisy)

    def replay(effect_specs, label):
        out = work / f"{name}_replay_{label}.csv"
        command = [mpdrig, "simulate", "--inputs", truth, "--cells", "50", "--sensor-noise",
                   "none", "--allow-negative-pressure", "--out", out, *base]
        for spec in effect_specs:
            command += ["--effect", spec]
        subprocess.run(command, check=True, capture_output=True, text=True)
        return read_log(out)

    replayed_both = replay(specs, "both")
    singles = [replay([spec], "only_" + spec.split(":")[0]) for spec in specs]
    truth_cols, noisy_cols = read_log(truth), read_log(noisy)
    channels = [c for c in truth_cols if c not in INPUTS]
    noise = {c: rms([a - b for a, b in zip(noisy_cols[c], truth_cols[c])]) for c in channels}
    # Visibility of effect k beyond its partner: both against the partner alone, same inputs.
    visibility = []
    for k in range(2):
        partner = singles[1 - k]
        visibility.append(max(rms([a - b for a, b in zip(replayed_both[c], partner[c])]) / noise[c]
                              for c in channels if noise[c] > 0))
    if not done:
        start = time.time()
        result = subprocess.run([mpdrig, "diagnose", noisy, "--json", json_path, "--quiet"],
                                capture_output=True, text=True)
        if result.returncode != 0:
            return dict(pair=pair, seed=seed, exc=exc_name, error=result.stderr.strip()[-300:])
        time_path.write_text(f"{time.time() - start:.2f}\n")
    wall = float(time_path.read_text())
    d = json.load(open(json_path))
    selected = [s["effect"] for s in d.get("selected", [])]
    equivalent = d.get("equivalent", []) or []
    # The two inlet compliances are one explanation where the compartment's own mode lies far
    # above the log's band (a lumped V/K either way): either names the other.
    def same(a, b):
        return a == b or {a, b} == INLET_COMPLIANCES
    named = [any(same(h, s) for s in selected + equivalent) for h in pair]
    false = [s for i, s in enumerate(selected)
             if not any(same(s, h) for h in pair)
             and not (i == 0 and any(same(h, e) for h in pair for e in equivalent))]
    steps = [d["baseline"]["error"]] + [s["error"] for s in d.get("selected", [])]
    # For each hidden effect not named: did diagnose's own detectability estimate (the weakest
    # strength this log could show, `detectable_from`, against the model it was last measured
    # against) put its threshold beyond the hidden strength? True, False, or None (not known).
    truth = {spec.split(":")[0]: spec for spec in specs}
    below = [None if n else below_detectability(d, h, truth.get(h, "")) for h, n in
             zip(pair, named)]
    return dict(pair=pair, seed=seed, exc=exc_name, visibility=visibility, selected=selected,
                below=below,
                named=named, false=false, steps=steps, wall=wall)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    repo = pathlib.Path(__file__).resolve().parent.parent
    parser.add_argument("--build-dir", default=os.environ.get("BUILD_DIR", repo / "build"))
    parser.add_argument("--pairs", default="all", help="all, or A+B,C+D,...")
    parser.add_argument("--seeds", default="1-1", help="FIRST-LAST")
    parser.add_argument("--duration", type=float, default=40.0)
    parser.add_argument("--rate", type=float, default=50.0)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--visible", type=float, default=1.5,
                        help="visibility (noise RMS) from which an effect counts as visible")
    parser.add_argument("--work", default=None)
    parser.add_argument("--reuse", action="store_true",
                        help="keep the logs and diagnoses already in --work (a run cut short)")
    parser.add_argument("--keep-logs", action="store_true",
                        help="diagnose the logs already in --work again (another build on the same logs)")
    args = parser.parse_args()
    mpdrig = pathlib.Path(args.build_dir) / "tools" / "mpdrig"
    if not mpdrig.exists():
        sys.exit(f"error: {mpdrig} not built (./deploy/build.sh)")
    work = pathlib.Path(args.work or tempfile.mkdtemp(prefix="pairs_"))
    work.mkdir(parents=True, exist_ok=True)
    all_pairs = [p for p in itertools.combinations(CATALOGUE, 2)
                 if not any(set(p) <= e for e in EXCLUSIVE)]
    if args.pairs == "all":
        pairs = all_pairs
    else:
        pairs = [tuple(p.split("+")) for p in args.pairs.split(",")]

    def position(pair):  # in the whole list, so that a subset gets each pair's own excitation
        for i, p in enumerate(all_pairs):
            if set(p) == set(pair):
                return i
        return len(all_pairs)
    first, last = (int(x) for x in args.seeds.split("-"))
    # The excitation rotates along the pairs and shifts by one per seed: each pair meets another.
    cases = [(pair, seed, position(pair) + seed - 1) for seed in range(first, last + 1)
             for pair in pairs]
    print(f"{len(cases)} logs, work dir {work}", file=sys.stderr)
    out = open(work / "pairs.txt", "w")

    def emit(line):
        print(line)
        out.write(line + "\n")
        out.flush()

    emit(f"{'hidden pair':44} {'seed':>4} {'excitation':11} {'visible':>11}  {'selected':44} "
         f"{'both':>4} {'false':>5} {'wall_s':>6}  error % step by step")
    results = []
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        futures = [pool.submit(run_case, mpdrig, work, *c, args.duration, args.rate, args.reuse,
                               args.keep_logs)
                   for c in cases]
        for future in concurrent.futures.as_completed(futures):
            try:
                r = future.result()
            except Exception as e:  # a synth or a log that failed: say so, go on
                emit(f"case failed: {e}")
                continue
            results.append(r)
            label = "+".join(r["pair"])
            if "error" in r:
                emit(f"{label:44} {r['seed']:4d} {r['exc']:11} diagnose failed: {r['error']}")
                continue
            vis = "/".join(f"{v:.1f}" for v in r["visibility"])
            steps = " -> ".join(f"{100 * e:.2f}" for e in r["steps"])
            emit(f"{label:44} {r['seed']:4d} {r['exc']:11} {vis:>11}  "
                 f"{'+'.join(r['selected']) or '-':44} {'yes' if all(r['named']) else 'no':>4} "
                 f"{len(r['false']):5d} {r['wall']:6.1f}  {steps}")
    ok = [r for r in results if "error" not in r]
    visible = [r for r in ok if min(r["visibility"]) >= args.visible]
    emit("")
    emit(f"logs: {len(results)}, diagnose failed: {len(results) - len(ok)}")
    emit(f"both visible (>= {args.visible} x noise RMS): {len(visible)}; both named in "
         f"{sum(all(r['named']) for r in visible)}; at least one named in "
         f"{sum(any(r['named']) for r in visible)}")
    emit(f"all logs: both named in {sum(all(r['named']) for r in ok)}, "
         f"false effects in {sum(bool(r['false']) for r in ok)} "
         f"({', '.join(sorted({f for r in ok for f in r['false']})) or 'none'})")
    per_effect = {}
    for r in visible:
        for h, n in zip(r["pair"], r["named"]):
            per_effect.setdefault(h, [0, 0])
            per_effect[h][0] += n
            per_effect[h][1] += 1
    emit("named where both visible, per effect: " +
         ", ".join(f"{h} {n}/{t}" for h, (n, t) in sorted(per_effect.items())))
    missed = [(h, b) for r in visible for h, b in zip(r["pair"], r["below"]) if b is not None]
    below_count = {}
    for h, b in missed:
        below_count.setdefault(h, [0, 0])
        below_count[h][0] += b
        below_count[h][1] += 1
    emit(f"missed where both visible: {len(missed)}, of them below diagnose's own detectability "
         f"estimate at the hidden strength: {sum(b for _, b in missed)} (" +
         ", ".join(f"{h} {b}/{t}" for h, (b, t) in sorted(below_count.items())) + ")")
    walls = [r["wall"] for r in ok]
    if walls:
        emit(f"diagnose wall: {min(walls):.1f}-{max(walls):.1f} s, total {sum(walls):.0f} s")


if __name__ == "__main__":
    main()
