#!/usr/bin/env bash
# Installs what is missing, builds Strata and starts strata-server with the demo scene on
# 127.0.0.1:7070 (README command 1). Extra arguments go to strata-server, e.g. --port 8080.
# It builds every tool the README uses afterwards (strata-server, the strata CLI, strata-demo),
# not the tests or benchmarks.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
STRATA_TARGETS="strata-server strata strata-demo" scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
exec build/server/strata-server --demo --host 127.0.0.1 --port 7070 "$@"
