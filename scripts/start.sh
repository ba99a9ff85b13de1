#!/usr/bin/env bash
# Installs what is missing, builds Strata and starts strata-server on 127.0.0.1:7070 with its
# data directory ./data (README command 1): the scene survives restarts and crashes; the demo
# scene is loaded only into an empty one. STRATA_DATA picks another directory. Extra arguments
# go to strata-server, e.g. --port 8080 or --fsync batch; --port, --host and --data given here
# replace the defaults rather than repeat them. It prints the viewer's URL (GET /).
# It builds every tool the README uses afterwards (strata-server, the strata CLI, strata-demo),
# not the tests or benchmarks. STRATA_START_DRY_RUN=1 only prints the server's command line.
set -euo pipefail
cd "$(dirname "$0")/.."

# True when the arguments give option $1, as "$1 value" or "$1=value".
given() {
    local name=$1
    shift
    for arg in "$@"; do
        case "$arg" in "$name" | "$name"=*) return 0 ;; esac
    done
    return 1
}

# The value of option $1 in the arguments, or $2.
value_of() {
    local name=$1 fallback=$2
    shift 2
    local args=("$@") i
    for ((i = 0; i < ${#args[@]}; ++i)); do
        case "${args[i]}" in
            "$name") [ $((i + 1)) -lt ${#args[@]} ] && fallback="${args[i + 1]}" ;;
            "$name"=*) fallback="${args[i]#"$name"=}" ;;
        esac
    done
    echo "$fallback"
}

defaults=(--demo)
given --host "$@" || defaults+=(--host 127.0.0.1)
given --port "$@" || defaults+=(--port 7070)
given --data "$@" || defaults+=(--data "${STRATA_DATA:-$PWD/data}")
command=(build/server/strata-server "${defaults[@]}" "$@")

if [ "${STRATA_START_DRY_RUN:-}" = 1 ]; then
    printf '%s\n' "${command[*]}"
    exit 0
fi
scripts/install-deps.sh
STRATA_TARGETS="strata-server strata strata-demo" scripts/build.sh build -DCMAKE_BUILD_TYPE=RelWithDebInfo
echo "start.sh: the live viewer will be at http://$(value_of --host 127.0.0.1 "$@"):$(value_of --port 7070 "$@")/ (the server logs it too)"
exec "${command[@]}"
