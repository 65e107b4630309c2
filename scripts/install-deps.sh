#!/usr/bin/env bash
# Installs SSTA's build and test dependencies from Debian 12 packages.
# Idempotent and non-interactive: run it as root (or with sudo) as often as you like.
set -euo pipefail

packages=(
  build-essential cmake ccache pkg-config
  libeigen3-dev libopencv-dev libpcl-dev liboctomap-dev libceres-dev
  libyaml-cpp-dev libpng-dev libjpeg-dev libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev
  # ROS bags: ROS 1 through rosbag and the message packages, ROS 2 (MCAP, sqlite3) read by SSTA
  librosbag-dev libsensor-msgs-dev libnav-msgs-dev libtf2-msgs-dev libgeometry-msgs-dev
  libzstd-dev liblz4-dev libsqlite3-dev
  # the Python API and its tests
  python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest python3-matplotlib
  # the fleet recipe and its test: a one-node Slurm cluster
  slurm-wlm slurmctld slurmd munge
  # the MCAP export's test: an independent reader on node (its npm packages: tests/mcap_reader/)
  nodejs
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Debian's npm, unless an npm is there already (a nodejs package from elsewhere brings its own).
command -v npm > /dev/null || missing+=(npm)
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
