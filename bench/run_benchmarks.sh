#!/usr/bin/env bash
# Builds (Release) and runs the simulator benchmarks and the frequency-response accuracy report,
# and prints a compact table (bench/README.md explains the numbers).
#
#   bash bench/run_benchmarks.sh [extra Google Benchmark flags]
#
# Environment:
#   BUILD_DIR       build directory (default: <repo>/build-bench)
#   REPETITIONS     benchmark repetitions; >1 reports the median (default: 1)
#   BENCH_FILTER    --benchmark_filter regex (default: all)
#   ACCURACY_CELLS  cell counts for the accuracy report (default: 100,1000; N=1000 takes ~1-2 min)
#   SKIP_ACCURACY   1 skips the accuracy report
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-${repo}/build-bench}"
repetitions="${REPETITIONS:-1}"
filter="${BENCH_FILTER:-.}"
accuracy_cells="${ACCURACY_CELLS:-100,1000}"

if [[ ! -f "${build_dir}/build.ninja" && ! -f "${build_dir}/Makefile" ]]; then
  generator=()
  command -v ninja >/dev/null && generator=(-G Ninja)
  cmake -S "${repo}" -B "${build_dir}" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DMPDRIG_BUILD_TESTS=OFF -DMPDRIG_BUILD_BENCHMARKS=ON
fi
build_type="$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "${build_dir}/CMakeCache.txt")"
if [[ "${build_type}" != "Release" ]]; then
  echo "error: ${build_dir} is configured as '${build_type}', not Release; set BUILD_DIR" >&2
  exit 1
fi
cmake --build "${build_dir}" --target mpdrig_simulator_benchmark mpdrig_accuracy_report

json="${build_dir}/bench/simulator_benchmark.json"
echo "== simulator benchmark ($(nproc) cores, load: $(cut -d' ' -f1-3 /proc/loadavg))"
"${build_dir}/bench/mpdrig_simulator_benchmark" \
  --benchmark_filter="${filter}" \
  --benchmark_repetitions="${repetitions}" \
  --benchmark_display_aggregates_only="$([[ ${repetitions} -gt 1 ]] && echo true || echo false)" \
  --benchmark_out="${json}" --benchmark_out_format=json \
  --benchmark_format=console "$@" >"${build_dir}/bench/simulator_benchmark.txt"

if command -v python3 >/dev/null; then
  python3 - "${json}" <<'EOF'
import json, re, sys

# Targets (bench/README.md): 20 s simulated in <= 0.1 s at N = 1000 and <= 5 ms at N = 100.
TARGET_MS = {100: 5.0, 1000: 100.0}
# Thesis Table 7.4.1 (ode45, C-MEX right-hand side), seconds for 20 s simulated.
THESIS_S = {("quasilinear", 10): 0.15, ("quasilinear", 100): 0.3, ("quasilinear", 1000): 8.0,
            ("linear", 10): 0.1, ("linear", 100): 0.17, ("linear", 1000): 4.2}
TO_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}

data = json.load(open(sys.argv[1]))
aggregated = any(b.get("run_type") == "aggregate" for b in data["benchmarks"])
rows = [b for b in data["benchmarks"]
        if (b.get("aggregate_name") == "median" if aggregated else b.get("run_type") == "iteration")]
# Iterations per repetition (an aggregate's own "iterations" is the number of repetitions).
iterations = {}
for b in data["benchmarks"]:
    if b.get("run_type") == "iteration":
        key = re.sub(r"/(min_time|iterations|real_time|repeats)[^/]*", "", b["run_name"])
        iterations.setdefault(key, b["iterations"])
if data["context"].get("library_build_type") == "debug":
    print("(note: the distribution's libbenchmark is a debug build; it does not touch the timed code)")
if aggregated:
    print(f"(median of {rows[0].get('repetitions', '?')} repetitions; iters: per repetition)")
print(f"{'benchmark':<50} {'time':>11} {'iters':>7} {'steps':>7} {'rtf':>9} "
      f"{'ns/cell/step':>12} {'thesis':>7}  target")
for b in rows:
    m = re.match(r"(BM_\w+)/(\w+)/(\w+)/N:(\d+)", b["run_name"])
    if not m:
        continue
    bench, model, scheme, cells = m.group(1), m.group(2), m.group(3), int(m.group(4))
    ms = b["real_time"] * TO_MS[b["time_unit"]]
    name = f"{bench}/{model}/{scheme}/N:{cells}"
    time = f"{ms:.3f} ms" if ms < 1e3 else f"{ms / 1e3:.2f} s"
    if bench == "BM_Step":
        time = f"{ms * 1e3:.2f} us"
    steps = f"{b['steps']:.0f}" if "steps" in b else ""
    rtf = "" if "rtf" not in b else f"{b['rtf']:.0f}" if b["rtf"] >= 10 else f"{b['rtf']:.2f}"
    per_cell = f"{b['ns_per_cell_step']:.2f}" if "ns_per_cell_step" in b else ""
    thesis, target = "", ""
    if bench == "BM_Simulate20s":
        if (model, cells) in THESIS_S:
            thesis = f"{THESIS_S[(model, cells)]:g} s"
        if cells in TARGET_MS and scheme == "characteristics":
            limit = TARGET_MS[cells]
            target = (f"<= {limit:g} ms: " +
                      ("met" if ms <= limit else f"MISSED ({ms / limit:.2f}x)"))
    if "error_message" in b:
        time, target = "error", b["error_message"]
    iters = iterations.get(name, b["iterations"])
    print(f"{name:<50} {time:>11} {iters:>7} {steps:>7} {rtf:>9} "
          f"{per_cell:>12} {thesis:>7}  {target}")
EOF
else
  cat "${build_dir}/bench/simulator_benchmark.txt"
fi
echo "(full output: ${build_dir}/bench/simulator_benchmark.txt, ${json})"

if [[ "${SKIP_ACCURACY:-0}" != "1" ]]; then
  echo
  echo "== frequency-response accuracy"
  "${build_dir}/bench/mpdrig_accuracy_report" --cells="${accuracy_cells}" --threads="$(nproc)"
fi
