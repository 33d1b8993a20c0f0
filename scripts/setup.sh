#!/usr/bin/env bash
# Installs every Debian package cblox needs to build, test and run (Debian 12, as root).
# Idempotent: safe to run again. Usage: scripts/setup.sh [--bench]
#   --bench   also install the benchmark peers (Open3D, Google Benchmark is always in), and
#             glog + protobuf for the voxblox peer (voxblox itself is not in Debian: that
#             peer needs a build of voxblox's core, see test/bench/CMakeLists.txt).
set -euo pipefail

packages=(
  build-essential cmake ninja-build ccache pkg-config git
  libeigen3-dev libabsl-dev libyaml-cpp-dev libopencv-dev
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev default-jdk-headless
  openjdk-17-jre libjchart2d-java xvfb
  libembree-dev libceres-dev libsuitesparse-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcivetweb-dev libjs-three chromium python3-websocket  # cblox-viewer and its browser test
  libsystemd-dev libcli11-dev nlohmann-json3-dev libzstd-dev zlib1g-dev libxxhash-dev libxml2-dev
  libv4l-dev libturbojpeg0-dev v4l-utils
  libcamera-dev opencv-doc
  iproute2 util-linux python3
  clang-14 libclang-rt-14-dev  # scripts/fuzz.sh: libFuzzer, ASan, UBSan
)
if [[ "${1:-}" == "--bench" ]]; then
  packages+=(libopen3d-dev libgoogle-glog-dev libprotobuf-dev protobuf-compiler)
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [[ ${#missing[@]} -eq 0 ]]; then
  echo "setup: all ${#packages[@]} packages already installed"
  exit 0
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
