#!/usr/bin/env bash
# Grades a student's controller: builds the student's directory into an image (its Containerfile,
# FROM localhost/mpdrig:latest), runs it against its own virtual rig beside a reference rig
# (docker-compose.yml: rig, reference, controller, recorder as separate containers) and judges
# what the recorder saw (judge.sh: PASS or FAIL, exit 0 or 1).
#
#   deploy/class/grade.sh deploy/class/example-controller           # -> PASS
#   deploy/class/grade.sh ~/students/ada /tmp/ada-run               # recordings kept there
#
# Needs the runtime image (deploy/container/build-images.sh), podman and docker-compose (v1)
# (deploy/install-deps.sh --containers), and root. Environment: DURATION_S (default 60),
# SENSOR_NOISE (default none), and judge.sh's MIN_ATTENUATION, MAX_MEAN_OFFSET_BAR,
# MEASURE_LAST_S. Exit 2: grading could not run (not the student's fault).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source "$here/../container/podman-env.sh"
student_dir="${1:?usage: grade.sh STUDENT_DIR [OUT_DIR]}"
[[ -f "$student_dir/Containerfile" ]] || { echo "grade.sh: $student_dir has no Containerfile" >&2; exit 2; }
name="$(basename "$(cd "$student_dir" && pwd)" | tr -c 'a-z0-9\n' '-')"
work="$(mktemp -d /tmp/mpdrig-grade.XXXXXX)"
out="${2:-$work/out}"
mkdir -p "$out"
export OUT_DIR="$(cd "$out" && pwd)"
export CONTROLLER_IMAGE="localhost/mpdrig-student-$name:latest"
project="mpdrig-grade-$name-$$"

service_pid=""
keep="${2:-}"
cleanup() {
  if [[ -n "${DOCKER_HOST:-}" ]]; then
    docker-compose -p "$project" -f "$here/docker-compose.yml" down -t 2 >/dev/null 2>&1 || true
  fi
  if [[ -n "$service_pid" ]]; then kill "$service_pid" 2>/dev/null; wait "$service_pid" 2>/dev/null; fi
  rm -rf "$work/podman.sock" "$work/sock"
  [[ -z "$keep" ]] && rm -rf "$work"
  true
}
trap cleanup EXIT

podman image exists "$MPDRIG_RUNTIME_IMAGE" ||
  { echo "grade.sh: no $MPDRIG_RUNTIME_IMAGE: run deploy/container/build-images.sh" >&2; exit 2; }
podman_build_replacing "$CONTROLLER_IMAGE" "$student_dir" ||
  { echo "FAIL: the controller directory does not build ($student_dir)"; exit 1; }

# docker-compose (v1) speaks the Docker API: podman serves it on a socket of our own.
if [[ -z "${DOCKER_HOST:-}" ]]; then
  podman system service --time=0 "unix://$work/podman.sock" >"$work/service.log" 2>&1 &
  service_pid=$!
  export DOCKER_HOST="unix://$work/podman.sock"
  for _ in $(seq 100); do [[ -S "$work/podman.sock" ]] && break; sleep 0.1; done
fi
compose=(docker-compose -p "$project" -f "$here/docker-compose.yml")
"${compose[@]}" up -d >"$work/compose.log" 2>&1 || { cat "$work/compose.log" >&2; exit 2; }
# The recorder ends when it has DURATION_S of both rigs (or 30 s after the last sample).
recorder="$("${compose[@]}" ps -q recorder)"
[[ -n "$recorder" ]] || { echo "grade.sh: the recorder did not start" >&2; cat "$work/compose.log" >&2; exit 2; }
podman wait "$recorder" >/dev/null || true
"${compose[@]}" logs --no-color >"$OUT_DIR/compose-logs.txt" 2>&1 || true
"${compose[@]}" down -t 2 >/dev/null 2>&1 || true
if [[ -n "${2:-}" ]]; then
  echo "grade.sh: $student_dir ($CONTROLLER_IMAGE): recordings and container logs in $OUT_DIR" >&2
fi
"$here/judge.sh" "$OUT_DIR"
