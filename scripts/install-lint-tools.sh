#!/usr/bin/env bash
# Installs the offline Dockerfile linter that scripts/check-docker.sh runs: npm's
# dockerfile-utils, exactly as pinned in docker/lint/package-lock.json, into
# docker/lint/node_modules (gitignored; never a global install). Node.js and npm come from Debian's nodejs and npm packages
# when npm is missing. Idempotent; installing Debian packages needs root (or sudo).
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
wanted="$(node -p "require('./$lint/package-lock.json')
                    .packages['node_modules/dockerfile-utils'].version")"
installed="$(node -p "try { require('./$lint/node_modules/dockerfile-utils/package.json').version }
                      catch (e) { '' }")"
if [ "$installed" = "$wanted" ]; then
    echo "install-lint-tools: dockerfile-utils $wanted present"
else
    echo "install-lint-tools: installing dockerfile-utils $wanted into $lint/node_modules"
    npm ci --prefix "$lint" --ignore-scripts --no-audit --no-fund --loglevel=error
fi
