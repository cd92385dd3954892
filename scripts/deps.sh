#!/usr/bin/env bash
# Installs the Debian 12 packages mrcheck needs to build, run and test.
# Skips apt entirely when everything is already there. Run as root.
set -euo pipefail
pkgs=(
  cmake make gcc g++ pkg-config
  libcjson-dev libstb-dev libtinygltf-dev libapriltag-dev libmeshoptimizer-dev
  libegl-dev libgl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri
  libglfw3-dev xvfb xauth xdotool fonts-dejavu-core
  libembree-dev
  libopencv-dev libopencv-contrib-dev
  libceres-dev libzip-dev
  unzip poppler-utils
  python3
  gltfpack libdraco-dev
  libifcplusplus-dev
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
