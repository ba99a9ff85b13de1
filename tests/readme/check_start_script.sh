#!/usr/bin/env bash
# scripts/start.sh's own arguments: each of --port, --host and --data appears once on the server's
# command line, the caller's value when given (as "--port 8080" or "--port=8080"), the default
# otherwise. (strata-server refuses an option given twice: "--port: At Most 1 required but
# received 2".)
set -euo pipefail
script=$1
fail=0
expect() {
    local want=$1
    shift
    local got
    got=$(STRATA_START_DRY_RUN=1 STRATA_DATA=/srv/scene "$script" "$@")
    if [ "$got" != "$want" ]; then
        echo "start.sh $*: got '$got', want '$want'" >&2
        fail=1
    fi
}
server=build/server/strata-server
expect "$server --demo --host 127.0.0.1 --port 7070 --data /srv/scene"
expect "$server --demo --host 127.0.0.1 --data /srv/scene --port 8080" --port 8080
expect "$server --demo --host 127.0.0.1 --data /srv/scene --port=8080 --fsync batch" --port=8080 --fsync batch
expect "$server --demo --port 7070 --host 0.0.0.0 --data /tmp/d" --host 0.0.0.0 --data /tmp/d
exit $fail
