#!/usr/bin/env bash
# The whole test suite built with AddressSanitizer and UndefinedBehaviorSanitizer, in its own build
# directory (${SANITIZE_BUILD_DIR:-<repo>/build-asan}): memory errors, leaks and undefined
# behaviour in our code fail the test that hit them. RelWithDebInfo at -O2 keeps it fast enough
# for CI; -g1 (line tables, no variables) still gives reports with files and lines and compiles in
# 30 % less time than -g (diagnose.cc: 25 s against 37 s). Run by .ci/run after the Release suite (docs/validation.md,
# "Fuzzing and the sanitizer build"); on its own: deploy/test-sanitize.sh [ctest arguments, e.g. -R riglog].
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${SANITIZE_BUILD_DIR:-$root/build-asan}"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMPDRIG_SANITIZE=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
  -DMPDRIG_BUILD_TESTS=ON -DMPDRIG_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)"
# Cyclone DDS and the other libraries are not instrumented; ASan still sees their memory through
# malloc. halt_on_error: the first report ends the test (and fails it).
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:abort_on_error=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# One seed per diagnose case (the Release suite runs three; the sanitizers look at the code paths,
# which one seed covers, and an instrumented diagnose is several times slower).
export MPDRIG_DIAGNOSE_CASES="${MPDRIG_DIAGNOSE_CASES:-1}"
# The container and network-namespace tests deploy the Release binaries (images, other hosts), the
# class SDK's test compiles the example controller from the sources with the SDK's own flags
# (label deploy: none of this build's code runs), and the interop test drives another vendor's DDS
# (Fast DDS 2.9, which itself trips ASan): they test the deployment and the wire, not our memory,
# and run in the Release suite.
# The statistical tests of the model (diagnose over the whole catalogue at two noise levels, the
# simulated frequency response on the method-of-lines scheme, the shadow at three heaves, the fit
# at lab noise) repeat the same code paths over more effects, seeds and excitations: that is what
# the Release suite checks, and it is most of this suite's time under the sanitizers (3-5x slower
# each). Here one case of most runs, so the sanitizers still see their paths: diagnose with and
# without a hidden effect, its forward selection of two, the simulated frequency response, the
# shadow. The frequency response's case is the characteristics scheme's (2 s of CPU here against
# the method of lines' 14.5 s): the SUNDIALS scheme's own path (mol_solver.cc, ARKODE) runs
# here in pipe_solver_test's and rig_validation_test's method-of-lines cases, which are not
# excluded. The 120 s diagnose at lab noise, the fit at lab noise and the method of lines'
# frequency responses run in the Release suite only (their paths are those of the cases that do
# run here, and of the fit and scheme tests that are not excluded). hello_controller's real-time
# run (65 s of wall time) and its second lockstep heave take the paths of its lockstep demo run
# and its signal test, which do run here. The diagnoses of an irregular sea, of pressure floors
# (column separation from another grid) and of logs with regimes are more diagnoses: their own
# code (the sea, cavity_evidence, regimes, residual_signature) runs here in its unit tests and in
# every diagnosis of the one_each cases. MPDRIG_SANITIZE_ALL=1 runs them all.
repeats='HiddenResonanceEffects|DiagnoseHiddenEffect|DiagnoseWithoutHiddenEffect|DiagnoseAtLabNoise|SelectionOf|SimulatedVsAnalytic|ShadowAtLabNoise|WaveSpeedAndFrictionAtLabNoise|HelloControllerRealTime|HelloControllerLockstep.*/high_flow|DiagnoseIrregularSea|CavityEvidenceDiagnose|DiagnoseWithRegimes|DiagnoseWithoutRegimes'
# (ctest's names of parameterised tests go on with "  # GetParam() = ...": no $ anchors)
one_each='HiddenResonanceEffects.*/tubes_and_gas_sweep |DiagnoseHiddenEffect.*/sensor_lag_lab |DiagnoseWithoutHiddenEffect.*/lab |SelectionOfTwoHiddenEffects.*/sensor_lag_gas_entrainment_seed1 |SimulatedVsAnalytic.*/QuasiLinearCharacteristicsOpen |ShadowAtLabNoise.*/fast_0p8Hz '
# One test more than the cores, as deploy/test.sh: the suite waits on DDS and processes a lot.
if [[ "${MPDRIG_SANITIZE_ALL:-0}" == 1 ]]; then repeats='^$'; fi
ctest --test-dir "$build" -j"$(($(nproc) + 1))" --output-on-failure --timeout 1800 \
  -LE 'container|netns|interop|deploy' -E "$repeats" "$@"
if [[ "$repeats" != '^$' ]]; then
  ctest --test-dir "$build" -j"$(($(nproc) + 1))" --output-on-failure --timeout 1800 -R "$one_each" "$@"
fi
