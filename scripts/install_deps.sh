#!/usr/bin/env bash
# Installs groundslam's Debian 12 dependencies when they are missing. Idempotent: installs nothing
# when every package is present, so `make build` stays fast after the first time.
#   scripts/install_deps.sh          what `make build`, `make test` and `make demo` need
#   scripts/install_deps.sh --fuzz   also clang and its libFuzzer runtime, for `make fuzz`
#   scripts/install_deps.sh --benchmarks   also python3-skimage (its photo of gravel is a benchmark texture)
set -euo pipefail

packages=(
  cmake make g++ pkg-config
  libopencv-dev libceres-dev libeigen3-dev libyaml-cpp-dev libcli11-dev libpng-dev libjpeg-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-numpy python3-matplotlib python3-dev pybind11-dev python3-pytest
  chromium fonts-dejavu-core
)
if [ "${1:-}" = "--fuzz" ]; then
  packages+=(clang libclang-rt-14-dev)
fi
if [ "${1:-}" = "--benchmarks" ]; then
  packages+=(python3-skimage)
fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "groundslam: installing missing Debian packages: ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    sudo_cmd=(sudo)
  else
    echo "groundslam: need root (or sudo) to install: ${missing[*]}" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
