#!/usr/bin/env bash
# Installs the Debian 12 packages mpdrig needs, if any are missing. Non-interactive and
# idempotent: a second run installs nothing and does not touch the network.
#
#   deploy/install-deps.sh                # build, run and test mpdrig
#   deploy/install-deps.sh --containers   # and the container tools (deploy/container, deploy/class)
set -euo pipefail

containers=0
for arg in "$@"; do
  case "$arg" in
    --containers) containers=1 ;;
    *) echo "deploy/install-deps.sh: unknown option $arg (--containers)" >&2; exit 2 ;;
  esac
done

packages=(
  g++ cmake ninja-build
  libeigen3-dev          # linear algebra
  libsundials-dev        # ARKODE for the method-of-lines scheme (pulls MPI/PETSc: ~700 MB)
  libprotobuf-dev protobuf-compiler  # rig configuration files
  libcli11-dev           # command line
  libcpp-httplib-dev     # the dashboard's web server (clients/dashboard)
  cyclonedds-dev cyclonedds-tools  # DDS service: C API, headers and idlc (the IDL compiler)
  libgtest-dev libgmock-dev libbenchmark-dev  # tests and benchmarks
  libfftw3-dev pkg-config  # spectra for `mpdrig compare` (bands, lag, transfer functions)
  libceres-dev           # `mpdrig fit`: bounded nonlinear least squares and covariance
  nlohmann-json3-dev     # every JSON mpdrig writes or reads (header-only)
  # headless browser for the test that renders the comparison report (tests/tools/report/report_test),
  # and its WebDriver with Selenium for the dashboard's test (tests/clients/dashboard_test.py)
  chromium chromium-driver python3-selenium
  # DDS Security for a class (deploy/security/make-class): the CA, identities, signed
  # governance and permissions; tshark for the test that reads the wire (tests/security);
  # libssl-dev: a participant checks that its private key belongs to its certificate
  openssl tshark libssl-dev
  # Python client module (clients/python): bindings, numpy arrays, its tests and the live plot
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
  # another DDS vendor against the service, as ROS 2 and MATLAB's DDS Blockset use it
  # (tests/clients/fastdds_interop_test): eProsima Fast DDS, test only
  libfastrtps-dev
)
if [ "$containers" -eq 1 ]; then
  packages+=(
    podman runc          # images and containers; runc because crun 1.8 fails on these machines' cgroups
    debootstrap          # the Debian 12 base image, without an image registry
    docker-compose       # compose files (v1) against podman's API socket
    iproute2             # network namespaces and veth pairs for the several-hosts test
  )
fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "deploy/install-deps.sh: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "deploy/install-deps.sh: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq "${missing[@]}" >/dev/null
echo "deploy/install-deps.sh: done"
