#!/usr/bin/env bash
# Installs what is missing, builds Strata and runs the demo: it builds the demo scene, plays a
# short edit sequence, prints each launch's rebuild report and writes PNG frames to frames/.
# This is README command (1).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
STRATA_TARGETS=strata-demo scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
exec build/engine/strata-demo --out frames "$@"
