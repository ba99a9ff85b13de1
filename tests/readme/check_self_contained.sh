#!/bin/bash
# Tests, scripts, CI and build files read nothing beside the repository: no path leaves it
# ("../" above the top, or the developers' ../shared folder). Debian's installed packages
# (/usr/share/...) are dependencies, installed by scripts/install-deps.sh, not neighbours.
set -u
cd "$1" || exit 2
found=$(git grep -n -E '\.\./shared|\$\{PROJECT_SOURCE_DIR\}/\.\.|\$\{CMAKE_SOURCE_DIR\}/\.\.' \
    -- tests scripts .ci docker CMakeLists.txt '*/CMakeLists.txt' '*.cmake' \
    ':!tests/readme/check_self_contained.sh' ':!*.md' 2>/dev/null)
if [ -n "$found" ]; then
    echo "these lines reach outside the repository:"
    echo "$found"
    exit 1
fi
echo "nothing reaches outside the repository"
