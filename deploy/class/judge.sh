#!/usr/bin/env bash
# Pass or fail from what the recorder saw: the bottom-hole pressure (PT1) swing of the student's
# rig against the reference rig (same heave, choke fixed), both recorded by rig_echo.
#
#   deploy/class/judge.sh OUT_DIR    # reads OUT_DIR/student.csv and OUT_DIR/reference.csv
#
# Criteria (environment): over the last MEASURE_LAST_S (default 20) s of rig time,
#   - the PT1 half peak-to-peak swing is at least MIN_ATTENUATION (default 5) times smaller than
#     the reference's,
#   - the mean PT1 stays within MAX_MEAN_OFFSET_BAR (default 0.1) of the reference's (a controller
#     may not buy a small swing by dumping the pressure),
#   - both recordings reach DURATION_S (default 60) s of rig time less one second (a controller
#     that crashed or stopped stepping its rig fails).
# Prints one line per rig and PASS or FAIL with the reason; exit 0 on PASS, 1 on FAIL.
set -euo pipefail
out="${1:?usage: judge.sh OUT_DIR}"
window="${MEASURE_LAST_S:-20}"
min_ratio="${MIN_ATTENUATION:-5}"
max_offset="${MAX_MEAN_OFFSET_BAR:-0.1}"
duration="${DURATION_S:-60}"

# half peak-to-peak and mean of PT1 (column PT1_barg) over the last $window s; last time; rows
stats() {
  awk -F, -v w="$window" '
    /^#/ { next }
    !col { for (i = 1; i <= NF; ++i) if ($i == "PT1_barg") col = i; if (!col) exit 2; next }
    { t[n] = $1; p[n] = $col; ++n }
    END {
      if (n == 0) { print "0 0 0 0"; exit }
      last = t[n - 1]; lo = 1e300; hi = -1e300; s = 0; m = 0
      for (i = 0; i < n; ++i) if (t[i] >= last - w) { lo = p[i] < lo ? p[i] : lo; hi = p[i] > hi ? p[i] : hi; s += p[i]; ++m }
      printf "%.5f %.5f %.3f %d\n", (hi - lo) / 2, s / m, last, n
    }' "$1"
}

fail() { echo "FAIL: $*"; exit 1; }
for rig in reference student; do
  [[ -s "$out/$rig.csv" ]] || fail "no recording of rig $rig ($out/$rig.csv)"
done
read -r ref_amp ref_mean ref_last ref_n < <(stats "$out/reference.csv")
read -r stu_amp stu_mean stu_last stu_n < <(stats "$out/student.csv")
printf 'reference: PT1 swing %.4f bar (half peak-to-peak), mean %.3f barg, %d samples to t=%s s\n' "$ref_amp" "$ref_mean" "$ref_n" "$ref_last"
printf 'student:   PT1 swing %.4f bar (half peak-to-peak), mean %.3f barg, %d samples to t=%s s\n' "$stu_amp" "$stu_mean" "$stu_n" "$stu_last"
for pair in "reference $ref_last" "student $stu_last"; do
  set -- $pair
  awk -v t="$2" -v d="$duration" 'BEGIN { exit !(t >= d - 1) }' || fail "rig $1 recorded only to t=$2 s of $duration s"
done
ratio="$(awk -v a="$ref_amp" -v b="$stu_amp" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 1e9) }')"
offset="$(awk -v a="$ref_mean" -v b="$stu_mean" 'BEGIN { d = b - a; printf "%.3f", d }')"
awk -v r="$ratio" -v m="$min_ratio" 'BEGIN { exit !(r >= m) }' ||
  fail "BHP swing attenuated ${ratio}x, needs ${min_ratio}x (last ${window} s)"
awk -v o="$offset" -v m="$max_offset" 'BEGIN { exit !(o <= m && -o <= m) }' ||
  fail "mean BHP moved ${offset} bar from the reference's, at most ${max_offset} allowed"
echo "PASS: BHP swing attenuated ${ratio}x (needs ${min_ratio}x), mean ${offset} bar from the reference's (last ${window} s)"
