#!/usr/bin/env bash
# Installs the Debian (bookworm) packages that the build, the tests and the real-client checks
# need, then the browser viewer's pinned npm packages (scripts/npm/package-lock.json: three.js,
# esbuild, playwright-core, pngjs, ajv-cli, gltf-validator) into scripts/npm/node_modules (not committed).
# Idempotent: when everything is present it changes nothing and only says so.
# Works as root or through sudo. Set INSTALL_DEPS_DRY_RUN=1 to only list what is missing.
set -euo pipefail

packages=(
    # toolchain
    cmake ninja-build g++ make pkg-config clang-format
    # libraries
    libopencv-dev libopencv-contrib-dev libpcl-dev libeigen3-dev nlohmann-json3-dev
    libglm-dev libtinygltf-dev libstb-dev catch2 libcli11-dev zlib1g-dev libdeflate-dev
    # headless OpenGL: GLVND EGL/OpenGL + Mesa's EGL and llvmpipe drivers
    libegl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri
    # real clients used by the tests: JSON Schema validator, CloudCompare, PCL tools
    python3 python3-jsonschema python3-numpy cloudcompare pcl-tools
    # GNU time: the peak memory of each run of the bad-input corpus
    time
    # the Debian package (cpack's DEB generator reads library dependencies with dpkg-shlibdeps)
    dpkg-dev
    # plots for docs/performance.md
    python3-matplotlib
    # OpenCV's random trees and PNG reader for scripts/train-segment-classifier.py
    python3-opencv
    # the browser viewer: node runs npm and esbuild; the browser tests drive Debian's chromium
    nodejs chromium
    # scene-render play encodes drives to MP4 with it (found at run time)
    ffmpeg
    # a throw-away single-node Slurm for the cluster test (scripts/slurm/local-cluster.sh)
    slurm-wlm munge iproute2
)

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done

# The viewer's npm packages, exactly as locked; reinstalled only when the lock file changes.
install_npm() {
    local dir
    dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/scripts/npm"
    local stamp="$dir/node_modules/.stereoscene-lock"
    if [ -f "$stamp" ] && cmp -s "$stamp" "$dir/package-lock.json"; then
        return 0
    fi
    if [ "${INSTALL_DEPS_DRY_RUN:-0}" = 1 ]; then
        echo "install-deps: missing: npm packages of scripts/npm" >&2
        return 0
    fi
    if ! command -v npm >/dev/null 2>&1; then
        echo "install-deps: warning: npm not found; the viewer and its browser tests are skipped" >&2
        return 0
    fi
    (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >&2)
    cp "$dir/package-lock.json" "$stamp"
    echo "install-deps: installed the npm packages of scripts/npm" >&2
}

if [ ${#missing[@]} -eq 0 ]; then
    echo "install-deps: all ${#packages[@]} packages present" >&2
    install_npm
    exit 0
fi

echo "install-deps: missing: ${missing[*]}" >&2
if [ "${INSTALL_DEPS_DRY_RUN:-0}" = 1 ]; then
    exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
        sudo_cmd=(sudo)
    else
        echo "install-deps: error: not root and sudo is not available; install: ${missing[*]}" >&2
        exit 1
    fi
fi

export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: installed ${#missing[@]} packages" >&2
# Debian's nodejs ships npm separately (NodeSource's includes it).
command -v npm >/dev/null 2>&1 || "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends npm >/dev/null
install_npm
