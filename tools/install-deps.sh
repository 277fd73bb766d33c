#!/usr/bin/env bash
# Installs the Debian 12 packages Loom builds and runs with. Idempotent: does nothing when
# everything is present. Needs root or sudo.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools libglvnd0
  glslang-dev glslang-tools
  nlohmann-json3-dev libfmt-dev libglm-dev
  libopenexr-dev libpng-dev libjpeg62-turbo-dev libstb-dev zlib1g-dev
  libembree-dev
  liblua5.4-dev
  libimgui-dev libglfw3-dev xvfb xauth
  libtinyobjloader-dev libtinygltf-dev libpugixml-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev
  slurmctld slurmd slurm-client munge
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "loom: all Debian packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "loom: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
echo "loom: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
