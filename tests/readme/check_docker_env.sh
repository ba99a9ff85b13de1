#!/bin/bash
# Usage: check_docker_env.sh STRATA_SERVER DOCKER_README
# Fails naming each STRATA_* variable the server reads that the README's table lacks.
set -euo pipefail
server="$1" readme="$2"
missing=0
for var in $("$server" --help | grep -o 'STRATA_[A-Z_]*' | sort -u) STRATA_TOKEN; do
    if ! grep -q "\`$var\`" "$readme"; then
        echo "$readme does not document $var"
        missing=1
    fi
done
exit "$missing"
