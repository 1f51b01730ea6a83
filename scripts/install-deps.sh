#!/usr/bin/env bash
# Installs the Debian 12 packages softbody needs, and only those that are missing.
# clang (with its sanitizer runtimes, libFuzzer and OpenMP) builds the TSan and fuzz stages of CI;
# clang-format checks the formatting (scripts/check-format.sh). Blender (headless) reads the
# exports back in the tests (tests/export). The Python module: pybind11 and python3-dev to build
# it, numpy (also what Blender's glTF importer needs) and pytest to test it.
# Safe to run repeatedly; needs root (or sudo) only when something is missing.
set -euo pipefail
packages=(
  cmake g++ make pkg-config libgtest-dev libbenchmark-dev
  libglfw3-dev libglm-dev libimgui-dev libeigen3-dev
  libstb-dev nlohmann-json3-dev libcli11-dev
  xvfb xauth libgl1-mesa-dri mesa-utils x11-apps imagemagick xdotool
  clang clang-format libclang-rt-14-dev libfuzzer-14-dev libomp-14-dev
  blender python3-dev pybind11-dev python3-numpy python3-pytest
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "softbody: installing missing packages: ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "softbody: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
