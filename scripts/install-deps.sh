#!/usr/bin/env bash
# Installs the Debian 12 packages padsim needs to build, test and plot, when missing.
# Idempotent: when everything is present it only checks and returns.
# Usage: scripts/install-deps.sh [--bench]   (--bench adds SUNDIALS for the IDA comparison)
set -euo pipefail

packages=(
  cmake g++ make pkg-config clang libclang-rt-14-dev
  libeigen3-dev libsuitesparse-dev libboost-dev libcli11-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  ngspice gnuplot-nox
)
if [[ "${1:-}" == "--bench" ]]; then
  packages+=(libsundials-dev)
fi

missing=()
for package in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$package" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$package")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
sudo=""
[[ $(id -u) -eq 0 ]] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
