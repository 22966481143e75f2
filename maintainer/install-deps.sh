#!/usr/bin/env bash
# Install every build and run dependency of PyOIF from Debian's packages.
# Idempotent and quiet; run as root on a fresh Debian 12 machine.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git clang-format
  libeigen3-dev pybind11-dev
  libopenmpi-dev openmpi-bin
  libgtest-dev googletest
  python3 python3-dev python3-numpy python3-mpi4py python3-h5py
  python3-vtk9 python3-matplotlib python3-meshio python3-pybind11 python3-scipy python3-tqdm
  python3-ezdxf python3-svgelements python3-pil
  python3-sphinx python3-myst-parser python3-sphinx-rtd-theme
  ipython3 python3-ipykernel jupyter-notebook python3-nbclient python3-nbformat python3-nbconvert xvfb
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ "${#missing[@]}" -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} Debian packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
