#!/usr/bin/env bash
# Installs every Debian package weathergs uses. This is the only place the list lives.
# Idempotent: packages already installed are skipped; nothing is done when all are present.
# Works as root without sudo (or as a user with sudo), never asks questions.
set -euo pipefail

PACKAGES=(
  # build
  cmake ninja-build g++ pkg-config
  # C++ libraries
  libeigen3-dev libopencv-dev libopenimageio-dev openimageio-tools libembree-dev
  nlohmann-json3-dev libtbb-dev libcli11-dev libfmt-dev libsqlite3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # the learned restoration networks (restoration/led/lens_detector.cc)
  libtorch-dev
  # scene rendering and structure from motion
  blender colmap
  # the benchmark suite workflow (workflow/Snakefile)
  snakemake
  # photographs for the lens-drop detector's training crops (scripts/make-training-data.sh)
  mate-backgrounds
  # reference checks (scikit-image SSIM reference values, plots; its sample photos are training crops too)
  python3-numpy python3-skimage python3-matplotlib
)

# Optional groups, installed only when named: `install-deps.sh fuzz` (make fuzz), `install-deps.sh
# interop` (make interop: headless Chromium; Node.js and npm unless a node is already on PATH, e.g.
# from NodeSource; the npm packages themselves are pinned in interop/package.json), `install-deps.sh
# slurm` (make test-slurm: a one-node Slurm cluster started by the test itself).
for group in "$@"; do
  case "$group" in
    fuzz) PACKAGES+=(clang-14 libclang-rt-14-dev) ;;
    slurm) PACKAGES+=(slurm-wlm munge) ;;
    interop)
      PACKAGES+=(chromium)
      command -v node >/dev/null 2>&1 || PACKAGES+=(nodejs)
      command -v npm >/dev/null 2>&1 || PACKAGES+=(npm) ;;
    *) echo "install-deps: unknown group '$group' (known: fuzz, interop, slurm)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "install-deps: missing packages (${missing[*]}) and not root; install them as root" >&2
    exit 1
  fi
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
echo "install-deps: done"
