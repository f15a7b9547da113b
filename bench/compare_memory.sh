#!/usr/bin/env bash
# Peak memory and wall time of `mpdrig compare` on a long log (the target: "an hour at 1 kHz works in
# bounded memory"), measured with GNU time (`/usr/bin/time -v`, Debian package `time`).
#
#   bash bench/compare_memory.sh                     # 1 h at 1 kHz, all 16 compared channels
#   DURATION_S=600 bash bench/compare_memory.sh      # a shorter log, to see that memory is flat
#   COMMAND=simulate bash bench/compare_memory.sh    # `mpdrig simulate --inputs LOG` instead
#
# The log is made by `mpdrig simulate` (a 0.05 m, 0.2 Hz piston sine, choke 31 deg, pump 5 L/min;
# every lab channel, ~1.2 GB for an hour at 1 kHz) and kept for the next run.
#
# Environment:
#   MPDRIG      the binary (default: <repo>/build/tools/mpdrig)
#   DURATION_S  log length in seconds (default 3600)
#   RATE_HZ     sample rate (default 1000)
#   WORK_DIR    where the log and the outputs go (default: /tmp/mpdrig_compare_memory)
#   COMMAND     compare (default) or simulate (the log's inputs replayed into a log of every
#               channel, which streams the same way)
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mpdrig="${MPDRIG:-${repo}/build/tools/mpdrig}"
duration_s="${DURATION_S:-3600}"
rate_hz="${RATE_HZ:-1000}"
work="${WORK_DIR:-/tmp/mpdrig_compare_memory}"

if [[ ! -x "${mpdrig}" ]]; then
  echo "error: ${mpdrig} not found; build first (./deploy/build.sh) or set MPDRIG" >&2
  exit 1
fi
if [[ ! -x /usr/bin/time ]]; then
  echo "error: /usr/bin/time (GNU time) is missing: apt-get install time" >&2
  exit 1
fi
mkdir -p "${work}"
log="${work}/sine_${duration_s}s_${rate_hz}hz.csv"
if [[ ! -s "${log}" ]]; then
  echo "== generating ${log}"
  "${mpdrig}" simulate --piston sine:amp_m=0.05,freq_hz=0.2 --choke-deg 31 --pump-lpm 5 \
    --duration "${duration_s}" --rate-hz "${rate_hz}" --out "${log}" 2>/dev/null
fi
echo "== log: $(wc -c <"${log}") bytes, $(grep -vc '^#' "${log}") lines (header included)"
echo "== machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"

command="${COMMAND:-compare}"
case "${command}" in
  compare)
    /usr/bin/time -v "${mpdrig}" compare "${log}" --json "${work}/compare.json" \
      --report "${work}/compare.html" 2>"${work}/time.txt" | tee "${work}/stdout.txt"
    grep -E '^mpdrig compare: (read|replay) +100%' "${work}/time.txt" || true
    ;;
  simulate)
    /usr/bin/time -v "${mpdrig}" simulate --inputs "${log}" --out "${work}/replay.csv" \
      2>"${work}/time.txt" | tee "${work}/stdout.txt"
    ;;
  *)
    echo "error: COMMAND=${command}: compare or simulate" >&2
    exit 1
    ;;
esac
rss_kb="$(sed -n 's/^\s*Maximum resident set size (kbytes): //p' "${work}/time.txt")"
wall="$(sed -n 's/^\s*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "${work}/time.txt")"
cpu_user="$(sed -n 's/^\s*User time (seconds): //p' "${work}/time.txt")"
echo "== peak RSS ${rss_kb} kB ($((rss_kb / 1024)) MB), wall ${wall}, user CPU ${cpu_user} s"
