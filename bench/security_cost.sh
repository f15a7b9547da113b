#!/usr/bin/env bash
# The cost of DDS Security: bench/command_latency.sh without and then with security,
# the same run otherwise (1 kHz real-time rig, COUNT pump commands timed to the first sensor
# sample that shows them). Prints, per run, the latency quantiles, the probe's CPU, the
# service's CPU (its "s CPU (..% of one core)" line) and ddsperf's plain round trip for scale.
#   bash bench/security_cost.sh          # 2 x about 30 s
#   COUNT=1000 bash bench/security_cost.sh
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
for security in 0 1; do
  SECURITY=$security bash "$here/command_latency.sh"
  echo
done
