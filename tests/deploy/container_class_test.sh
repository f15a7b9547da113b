#!/usr/bin/env bash
# The containerised class test (ctest label `container`): builds the base and runtime images
# (deploy/container/build-images.sh, cached after the first run), checks that the runtime image
# holds the service and clients with no build tools, then grades two "students" with
# deploy/class/grade.sh: four containers each (rig, reference, the student's controller,
# recorder) in one private network namespace. The example controller must PASS (BHP swing
# attenuated at least 5x, as in tests/clients/bhp_controller_test: measured 18.7x), so must the
# same controller compiled in the build image (mpdrig-dev) from a student's two-stage
# Containerfile, and a controller that never moves the choke must FAIL (1.0x): the grader can
# tell them apart.
# Exit 77 (skipped, with the reason) where containers cannot run.
#   tests/deploy/container_class_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src="$1" build="$2"
source "$src/tests/deploy/skip_unless_containers.sh"
need_root "debootstrap and rootful podman"
need_commands podman debootstrap docker-compose runc
source "$src/deploy/container/podman-env.sh"
podman info >/dev/null 2>&1 || skip "podman cannot start: $(podman info 2>&1 | tail -1)"

start=$SECONDS
need_base_image_or_mirror
BUILD_DIR="$build" "$src/deploy/container/build-images.sh" --dev
echo "images ready in $((SECONDS - start)) s"
# podman itself may be installed yet unable to run containers here (cgroups, ulimits).
if ! err="$(podman run --rm --network none "$MPDRIG_RUNTIME_IMAGE" true 2>&1)"; then
  skip "podman cannot run a container on this machine: $err"
fi

# The runtime image: the three programs run, and there is no compiler in it.
echo "build image: $(podman image inspect --format '{{.Size}}' "$MPDRIG_DEV_IMAGE" | awk '{ printf "%.0f MB", $1 / 1e6 }')"
podman run --rm --network none "$MPDRIG_RUNTIME_IMAGE" sh -c '
  mpdrig --help >/dev/null && bhp_controller --help >/dev/null && rig_echo --help >/dev/null || exit 1
  for tool in gcc g++ cc c++ cpp clang ld make cmake; do
    if command -v "$tool" >/dev/null; then echo "build tool in the runtime image: $tool"; exit 1; fi
  done
  if dpkg-query -W -f "\${Package}\n" | grep -E -- "-dev\$"; then echo "-dev packages in the runtime image"; exit 1; fi'
echo "runtime image: $(podman image inspect --format '{{.Size}}' "$MPDRIG_RUNTIME_IMAGE" | awk '{ printf "%.0f MB", $1 / 1e6 }')"

t=$SECONDS
"$src/deploy/class/grade.sh" "$src/deploy/class/example-controller"
echo "graded the example controller in $((SECONDS - t)) s"
t=$SECONDS
"$src/deploy/class/grade.sh" "$src/deploy/class/cpp-controller"
echo "graded the compiled controller (built in the build image) in $((SECONDS - t)) s"
t=$SECONDS
if "$src/deploy/class/grade.sh" "$src/deploy/class/open-loop-controller"; then
  echo "error: a controller that never moves the choke passed"; exit 1
fi
echo "graded the open-loop controller in $((SECONDS - t)) s; total $((SECONDS - start)) s"
