#!/usr/bin/env bash
# Installs what is missing, builds Strata and starts strata-server with the demo scene on
# 127.0.0.1:7070 (README command 1). Extra arguments go to strata-server, e.g. --port 8080.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
STRATA_TARGETS=strata-server scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
exec build/server/strata-server --demo --host 127.0.0.1 --port 7070 "$@"
