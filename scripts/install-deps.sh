#!/bin/sh
# Installs the Debian 12 packages raybundle needs to build, render and test, and nothing from
# anywhere else. Fast when everything is present; the one list of packages is here.
# patchelf, debootstrap and xz-utils make and test the portable tarball (make dist, check-dist).
# chromium is for the tests alone: t0420 loads raybundle report's page in it, headless.
# --farm: also the single-node Slurm cluster `make check-farm` starts (slurm-wlm, munge).
set -eu

PACKAGES="
make gcc g++ pkg-config
libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
glslang-tools spirv-tools
libopenexr-dev libpng-dev
libopenimageio-dev openimageio-tools
libopencolorio-dev opencolorio-tools
libtinygltf-dev nlohmann-json3-dev
libembree-dev libmeshoptimizer-dev
libyaml-dev libxxhash-dev libjansson-dev
libcmocka-dev
mandoc man-db time clang-format
patchelf debootstrap xz-utils python3 libglvnd0 libx11-6 libxext6
libegl1 libglx0 libopengl0 libgl1 libgles2
chromium
"
if [ "${1:-}" = --farm ]; then
    PACKAGES="$PACKAGES slurm-wlm munge"
fi

missing=""
for p in $PACKAGES; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done
[ -z "$missing" ] && exit 0

if [ "$(id -u)" != 0 ]; then
    echo "install-deps: missing Debian packages:$missing" >&2
    echo "install-deps: run this script as root (or: sudo apt-get install$missing)" >&2
    exit 1
fi
echo "install-deps: installing$missing" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -q >&2
# shellcheck disable=SC2086
apt-get install -y -q --no-install-recommends $missing >&2
