#!/usr/bin/env bash
# Installs the Debian packages confluent needs. Idempotent; works as root or through sudo.
#   install-deps.sh [GROUP...]   groups: build (the default), sanitize, fresh
# This is the one list: ./dev calls it before every build, and CI runs ./dev in a brand-new
# Debian root (.ci/fresh-root.sh), so a package missing here fails CI.
set -euo pipefail
build=(
  build-essential cmake ninja-build pkg-config git ca-certificates
  libeigen3-dev libopencv-dev libceres-dev libsuitesparse-dev
  libegl-dev libgl-dev libepoxy-dev libegl-mesa0 libgl1-mesa-dri libglfw3-dev
  # libopenimageio-dev's CMake config exports targets for OIIO's tools and fails without them.
  libopenimageio-dev openimageio-tools nlohmann-json3-dev libtomlplusplus-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  ffmpeg xvfb xauth python3
)
# AddressSanitizer, UndefinedBehaviorSanitizer and libFuzzer come with Debian's clang.
sanitize=(clang libclang-rt-dev llvm)
# A brand-new Debian root for ./dev test --fresh and CI.
fresh=(mmdebstrap)

groups=("$@")
[ ${#groups[@]} -gt 0 ] || groups=(build)
packages=()
for group in "${groups[@]}"; do
  case "$group" in
    build) packages+=("${build[@]}") ;;
    sanitize) packages+=("${build[@]}" "${sanitize[@]}") ;;
    fresh) packages+=("${fresh[@]}") ;;
    *) echo "install-deps: unknown group '$group' (build, sanitize, fresh)" >&2; exit 2 ;;
  esac
done
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "install-deps: installing ${missing[*]}" >&2
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
