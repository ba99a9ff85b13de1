#!/usr/bin/env bash
# Configures and builds Strata with CMake and Ninja.
#   scripts/build.sh [BUILD_DIR] [extra CMake arguments...]    (default BUILD_DIR: build)
# Set STRATA_TARGETS to build only some targets (space separated).
set -euo pipefail
cd "$(dirname "$0")/.."
dir="${1:-build}"
[ $# -gt 0 ] && shift
cmake -S . -B "$dir" -G Ninja "$@" >/dev/null
if [ -n "${STRATA_TARGETS:-}" ]; then
    # shellcheck disable=SC2086
    cmake --build "$dir" --parallel "$(nproc)" --target ${STRATA_TARGETS}
else
    cmake --build "$dir" --parallel "$(nproc)"
fi
