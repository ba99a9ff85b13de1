#!/usr/bin/env bash
# Installs every Debian 12 package Strata needs. Idempotent; run as root (or with sudo).
#
#   scripts/install-deps.sh           build + test dependencies (default)
#   scripts/install-deps.sh --runtime only the shared libraries strata-server needs at run time
#
# README, .ci/run and docker/Dockerfile all call this one script (the runtime mode through
# docker/setup-runtime.sh). The Dockerfile linter is npm's: scripts/install-lint-tools.sh.
set -euo pipefail

mode=build
case "${1:-}" in
    --runtime) mode=runtime ;;
    --build|"") mode=build ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    *) echo "install-deps.sh: unknown option '$1' (use --build or --runtime)" >&2; exit 2 ;;
esac

# What strata-server's ELF NEEDED entries resolve to (readelf -d; libc6 is always there), and
# OpenEXR for the renderer. scripts/check-docker.sh fails if ldd finds a library missing.
runtime_pkgs=(
    libembree3-3 libtbb12 libopenexr-3-1-30 libpng16-16 libspdlog1.10 libfmt9 libcpp-httplib0.11
    libhiredis0.14 libstdc++6 libgcc-s1 libturbojpeg0 libdraco7 libseccomp2 libassimp5
)
build_pkgs=(
    build-essential cmake ninja-build pkg-config git ca-certificates curl
    libembree-dev libglm-dev libopenexr-dev nlohmann-json3-dev libcpp-httplib-dev libtbb-dev
    libgtest-dev libgmock-dev libbenchmark-dev libpng-dev zlib1g-dev libturbojpeg0-dev
    libtinygltf-dev libtinyobjloader-dev libcli11-dev libspdlog-dev
    libdraco-dev  # KHR_draco_mesh_compression glTF primitives (protocol/assets/draco_decode.cpp)
    libseccomp-dev  # the importers' sandboxed child process (protocol/assets/sandbox.cpp)
    libassimp-dev  # FBX, COLLADA, STL, 3DS, ... imports (protocol/assets/assimp_import.cpp)
    libhiredis-dev redis-server  # the shared edit log (server/replica) and its tests
    nginx  # test_compose_topology.py runs docker/nginx-replicas.conf as its child process
    clang libclang-rt-14-dev
    python3 python3-jsonschema python3-numpy python3-yaml
    python3-venv python3-pip  # pip install ./clients/python (test_install.py)
    chromium python3-websocket  # browser tests of the viewer (ctest -L browser, DevTools protocol)
    assimp-testmodels mmdebstrap
    mount  # scripts/check-docker.sh mounts inside its root; minimal Debian roots lack it
)

if [ "$mode" = runtime ]; then pkgs=("${runtime_pkgs[@]}"); else pkgs=("${build_pkgs[@]}"); fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi

missing=()
for p in "${pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

export DEBIAN_FRONTEND=noninteractive
# Refresh the package lists first. With everything already installed a failed refresh (no
# network) is only a warning, so the script stays usable offline.
if ! $sudo apt-get update -qq; then
    if [ "${#missing[@]}" -gt 0 ]; then
        echo "install-deps: apt-get update failed and packages are missing: ${missing[*]}" >&2
        exit 1
    fi
    echo "install-deps: apt-get update failed; all packages are present, continuing" >&2
fi
if [ "${#missing[@]}" -gt 0 ]; then
    echo "install-deps: installing ${missing[*]}"
    $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
    echo "install-deps: all ${#pkgs[@]} packages present"
fi
