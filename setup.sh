#!/usr/bin/env bash
# Installs the Debian packages isoscope needs to build and run (./setup.sh)
# or, with --tests, to build, test, fuzz, benchmark and package it.
# Idempotent: when every package is already installed it changes nothing and
# does not touch the network.
set -euo pipefail

# What building and running isoscope needs (README command 1).
PACKAGES=(
  # build; shaders are validated at build time; the manual page is made from --help
  build-essential cmake ninja-build pkg-config glslang-tools help2man
  # the linker (about three times faster than ld.bfd on our programs)
  lld
  # I/O
  libvtk9-dev libvtk-dicom-dev libteem-dev
  libopenvdb-dev libtbb-dev libglm-dev
  libopenimageio-dev
  # GL, GUI
  libepoxy-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev
  qt6-base-dev libqt6opengl6-dev
  # clusters and levels of detail of massive meshes (the simplifier)
  libmeshoptimizer-dev
  # convex hulls (the largest diameter of a structure)
  libqhull-dev
  # ray-traced ambient occlusion (and the tests' ground truth)
  libembree-dev
  # overlay text: FreeType rasterises DejaVu Sans, which fontconfig finds
  libfreetype-dev libfontconfig-dev fonts-dejavu-core
  # NIfTI reference library, CLI parsing, JSON output, zlib
  libnifti2-dev libcli11-dev nlohmann-json3-dev zlib1g-dev libssl-dev
  # MPI-distributed extraction (ISOSCOPE_MPI; VTK's MPI modules come with libvtk9-dev)
  libopenmpi-dev openmpi-bin
)
# What the test command adds (./setup.sh --tests): tests, benchmarks, fuzzing,
# GUI tests, shader validation, plots, the package and its checks.
TEST_PACKAGES=(
  libgtest-dev libgmock-dev libbenchmark-dev
  # fuzzing (clang's libFuzzer)
  clang libclang-rt-14-dev
  # GUI tests, benchmark plots, image tools
  xvfb xauth gnuplot-nox openimageio-tools
  # DICOM: vtk-dicom's and GDCM's and DCMTK's tools read back what we write
  vtk-dicom-tools libgdcm-tools dcmtk
  # the Debian package's checks: desktop entry, MIME types, manual page, lintian
  desktop-file-utils shared-mime-info man-db lintian
)
if [[ ${1:-} == --tests ]]; then PACKAGES+=("${TEST_PACKAGES[@]}"); fi

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
