#!/usr/bin/env bash
# Installs what is missing, builds Strata and starts strata-server on 127.0.0.1:7070 with its
# data directory ./data (README command 1): the scene survives restarts and crashes; the demo
# scene is loaded only into an empty one. STRATA_DATA picks another directory. Extra arguments
# go to strata-server, e.g. --port 8080 or --fsync batch. It prints the viewer's URL (GET /).
# It builds every tool the README uses afterwards (strata-server, the strata CLI, strata-demo),
# not the tests or benchmarks.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
STRATA_TARGETS="strata-server strata strata-demo" scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
port=7070
for ((i = 1; i <= $#; ++i)); do
    if [ "${!i}" = "--port" ] && [ $i -lt $# ]; then j=$((i + 1)); port="${!j}"; fi
done
echo "start.sh: the live viewer will be at http://127.0.0.1:${port}/ (the server logs it too)"
exec build/server/strata-server --demo --host 127.0.0.1 --port 7070 \
    --data "${STRATA_DATA:-$PWD/data}" "$@"
