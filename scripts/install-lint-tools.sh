#!/usr/bin/env bash
# Installs the offline linters, exactly as pinned in docker/lint/package-lock.json, into
# docker/lint/node_modules (gitignored; never a global install): npm's dockerfile-utils, which
# scripts/check-docker.sh runs on docker/Dockerfile, and @seriousme/openapi-schema-validator, which
# tests/protocol/check_openapi.py runs on GET /v1/openapi.json. Node.js and npm come from Debian's
# nodejs and npm packages when npm is missing. Idempotent; installing Debian packages needs root
# (or sudo).
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v npm >/dev/null; then
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    echo "install-lint-tools: installing Debian's nodejs and npm"
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq --no-install-recommends nodejs npm
fi

lint=docker/lint
# Every package pinned in the lockfile's top level must be installed at its pinned version.
missing="$(node -e "
    const lock = require('./$lint/package-lock.json');
    for (const name of Object.keys(lock.packages[''].dependencies)) {
        const wanted = lock.packages['node_modules/' + name].version;
        let installed = '';
        try { installed = require('./$lint/node_modules/' + name + '/package.json').version; }
        catch (e) {}
        if (installed !== wanted) console.log(name + '@' + wanted);
    }")"
if [ -z "$missing" ]; then
    echo "install-lint-tools: the pinned linters are present"
else
    echo "install-lint-tools: installing" $missing "into $lint/node_modules"
    npm ci --prefix "$lint" --ignore-scripts --no-audit --no-fund --loglevel=error
fi
