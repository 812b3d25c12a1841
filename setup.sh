#!/usr/bin/env bash
# Installs the Debian packages isoscope needs to build, test and benchmark.
# Idempotent: when every package is already installed it changes nothing and
# does not touch the network.
set -euo pipefail

PACKAGES=(
  # build
  build-essential cmake ninja-build pkg-config
  # I/O and the peer baselines
  libvtk9-dev libvtk-dicom-dev vtk-dicom-tools libteem-dev
  libopenvdb-dev libtbb-dev libglm-dev
  libopenimageio-dev openimageio-tools
  # GL, GUI
  libepoxy-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev
  qt6-base-dev libqt6opengl6-dev
  # ground truth
  libembree-dev
  # tests, fuzzing, GUI tests, shader validation
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev
  xvfb xauth glslang-tools
  # benchmark plots
  gnuplot-nox
  # overlay text: FreeType rasterises DejaVu Sans, which fontconfig finds
  libfreetype-dev libfontconfig-dev fonts-dejavu-core
  # NIfTI reference library, CLI parsing, JSON output, zlib
  libnifti2-dev libcli11-dev nlohmann-json3-dev zlib1g-dev libssl-dev
  # MPI-distributed extraction (ISOSCOPE_MPI; VTK's MPI modules come with libvtk9-dev)
  libopenmpi-dev openmpi-bin
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
