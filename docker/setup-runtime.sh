#!/usr/bin/env bash
# Prepares a Debian 12 root to run strata-server: the shared libraries it needs
# (scripts/install-deps.sh --runtime), the unprivileged user it runs as, and its data directory.
#
#   docker/setup-runtime.sh       as root, with scripts/install-deps.sh beside docker/
#
# docker/Dockerfile's runtime stage runs this script, and scripts/check-docker.sh runs it inside
# a fresh mmdebstrap root, so CI exercises the image's runtime steps. Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."

# The Dockerfile's USER, VOLUME and STRATA_DATA name the same values (scripts/check-docker.sh
# checks that they agree).
user=strata
uid=10001
gid=10001
data_dir=/data

scripts/install-deps.sh --runtime

if ! getent group "$user" >/dev/null; then
    groupadd --gid "$gid" "$user"
fi
if ! getent passwd "$user" >/dev/null; then
    # --no-log-init: no lastlog/faillog entries, which are sparse files sized by the UID.
    useradd --uid "$uid" --gid "$gid" --no-log-init --no-create-home --home-dir /nonexistent \
        --shell /usr/sbin/nologin --comment "strata-server" "$user"
fi
if [ "$(id -u "$user")" != "$uid" ] || [ "$(id -g "$user")" != "$gid" ]; then
    echo "setup-runtime: user '$user' exists with uid:gid $(id -u "$user"):$(id -g "$user")," \
        "expected $uid:$gid" >&2
    exit 1
fi
install -d -o "$uid" -g "$gid" -m 0750 "$data_dir"
echo "setup-runtime: runtime libraries installed; user $user ($uid:$gid) owns $data_dir"
