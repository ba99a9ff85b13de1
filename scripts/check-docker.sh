#!/usr/bin/env bash
# Checks docker/ without a Docker engine: what CI can prove about the image. A step of
# scripts/test.sh; also runs alone.
#
#   scripts/check-docker.sh [BUILD_DIR]      default build/ (strata-server is built if needed)
#
#   1. lint     docker/Dockerfile with npm's dockerfile-utils (scripts/install-lint-tools.sh
#               installs it); any warning or error fails.
#   2. spec     scripts/docker-spec.py reads the Dockerfile's runtime stage (ENV, USER, WORKDIR,
#               EXPOSE, VOLUME, HEALTHCHECK, ENTRYPOINT, the installed prefix) and checks
#               docker/docker-compose.yml against it; docker/README.md must document every
#               STRATA_* variable.
#   3. root     a fresh Debian 12 root (mmdebstrap --variant=minbase, the tarball cached in
#               build-docker/); docker/setup-runtime.sh runs inside it with chroot, as the
#               runtime stage's RUN does; `cmake --install` puts BUILD_DIR's binaries at the
#               prefix, as its COPY --from=build does; ldd must resolve every library.
#   4. run      strata-server started the way the image starts it: PID 1 of its own PID
#               namespace, as USER (no capabilities), in WORKDIR, with exactly the ENV, on a
#               read-only root with a writable VOLUME. Without a token it must refuse to start; with a mounted token
#               file and with STRATA_TOKEN it must turn healthy (HEALTHCHECK's command), answer
#               401 without the token and 200 with it, render, exit 0 on SIGTERM and never log
#               the token; with STRATA_INSECURE=1 it must serve without a token, and exit 0 on
#               SIGINT.
#
# Needs root (mmdebstrap, chroot, namespaces) and Debian's package mirror. Mounts exist only in
# private mount namespaces, so nothing stays mounted whatever happens; the root is deleted on exit
# (STRATA_KEEP_ROOT=1 keeps it for a look).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "$(id -u)" -ne 0 ]; then exec sudo "$0" "$@"; fi

repo="$(pwd -P)"
build="$(realpath -m "${1:-build}")"
work="$repo/build-docker"
root="$work/root"
logs="$work/logs"
started=$SECONDS

step() { printf '\n--> check-docker: %s\n' "$*"; }
fail() {
    echo "check-docker: FAILED: $*" >&2
    exit 1
}

# Deletes the root, but never while anything is mounted in it (rm -rf would follow a bind mount).
remove_root() {
    if awk -v r="$root" '$5 == r || index($5, r "/") == 1 { found = 1 } END { exit !found }' \
        /proc/self/mountinfo; then
        echo "check-docker: something is mounted under $root; not deleting it" >&2
        return 1
    fi
    rm -rf "$root"
}

# Cleanup: the processes of a scenario that did not finish (the unshare process, and its child
# whatever it has exec'd into by now), then the root.
pids=()
cleanup() {
    local pid children
    for pid in "${pids[@]}"; do
        children=()
        read -r -a children 2>/dev/null <"/proc/$pid/task/$pid/children" || true
        kill -KILL "${children[@]}" "$pid" 2>/dev/null || true
    done
    for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
    if [ "${STRATA_KEEP_ROOT:-0}" != 1 ]; then remove_root || true; fi
}
trap cleanup EXIT

# ---- 1. lint ----
step "lint docker/Dockerfile (dockerfile-utils)"
scripts/install-lint-tools.sh
lint() { node docker/lint/node_modules/dockerfile-utils/bin/dockerfile-utils lint "$@"; }
mkdir -p "$logs"
# The linter must see a problem where there is one, or a clean result proves nothing.
printf 'FROM debian:12-slim\nMAINTAINER nobody\n' >"$logs/canary.Dockerfile"
[ "$(lint --json "$logs/canary.Dockerfile")" != "[]" ] ||
    fail "the linter flags nothing in a bad file"
if [ "$(lint --json docker/Dockerfile)" != "[]" ]; then
    lint docker/Dockerfile || true
    fail "docker/Dockerfile has lint warnings or errors (above)"
fi
echo "docker/Dockerfile: no warnings"

# ---- 2. spec ----
step "runtime stage of docker/Dockerfile, docker/docker-compose.yml, docker/README.md"
spec="$(/usr/bin/python3 scripts/docker-spec.py docker/Dockerfile docker/docker-compose.yml)" ||
    fail "docker/Dockerfile or docker/docker-compose.yml (above)"
eval "$spec"
printf '  %s\n' "user $RT_USER, workdir $RT_WORKDIR, port $RT_PORT, volume $RT_VOLUME," \
    "prefix $RT_PREFIX, entrypoint ${RT_ENTRYPOINT[*]}, healthcheck ${RT_HEALTHCHECK[*]}" \
    "env ${RT_ENV[*]}"
STRATA_TARGETS=strata-server scripts/build.sh "$build"
server_bin="$build/server/strata-server"
tests/readme/check_docker_env.sh "$server_bin" docker/README.md ||
    fail "docker/README.md does not document every STRATA_ variable (above)"
grep -qF "docker build -f docker/Dockerfile" docker/README.md ||
    fail "docker/README.md has no build command"

# ---- 3. root ----
step "Debian 12 root: mmdebstrap, then docker/setup-runtime.sh inside it (chroot)"
mirrors=(
    "deb http://deb.debian.org/debian bookworm main"
    "deb http://deb.debian.org/debian bookworm-updates main"
    "deb http://deb.debian.org/debian-security bookworm-security main"
)
key="$(printf '%s\n' minbase "$(mmdebstrap --version)" "${mirrors[@]}" | sha256sum | cut -c1-16)"
base="$work/cache/minbase-$key.tar"
mkdir -p "$work/cache/apt-archives/partial"
# A week-old base is rebuilt, so that it does not drift far from what debian:12-slim is.
if [ -f "$base" ] && [ -z "$(find "$base" -mtime +7)" ]; then
    echo "base root: cached $base"
else
    t=$SECONDS
    rm -f "$work"/cache/minbase-*.tar
    mmdebstrap --variant=minbase --format=tar --quiet bookworm "$work/cache/partial.tar" \
        "${mirrors[@]}"
    mv "$work/cache/partial.tar" "$base"
    echo "base root: built in $((SECONDS - t)) s"
fi
remove_root || fail "cannot start from a fresh root"
mkdir -p "$root"
tar -C "$root" -xf "$base"
cp /etc/resolv.conf "$root/etc/resolv.conf"
# The runtime stage's RUN: the same two scripts at the same place, then the same clean-up.
mkdir -p "$root/tmp/strata-setup/scripts" "$root/tmp/strata-setup/docker"
cp scripts/install-deps.sh "$root/tmp/strata-setup/scripts/"
cp docker/setup-runtime.sh "$root/tmp/strata-setup/docker/"
t=$SECONDS
# Downloaded packages are kept in build-docker/cache/apt-archives for the next run.
# shellcheck disable=SC2016 # expanded by the inner bash
unshare --mount --fork -- bash -euc '
    mount -t proc proc "$1/proc"
    mount --rbind /dev "$1/dev"
    mount --bind "$2" "$1/var/cache/apt/archives"
    exec chroot "$1" /tmp/strata-setup/docker/setup-runtime.sh' _ "$root" "$work/cache/apt-archives"
rm -rf "$root/tmp/strata-setup" "$root"/var/lib/apt/lists/*
echo "runtime setup: $((SECONDS - t)) s"
# The runtime stage's COPY --from=build of what `cmake --install` put at the prefix.
DESTDIR="$root" cmake --install "$build" --prefix "$RT_PREFIX" --strip >/dev/null
[ -x "$root$RT_PREFIX/bin/strata-server" ] || fail "cmake --install put no bin/strata-server"

libs="$(chroot "$root" ldd "$RT_PREFIX/bin/strata-server")"
if grep -q "not found" <<<"$libs"; then
    echo "$libs" >&2
    fail "libraries missing from the runtime root: add their packages to install-deps.sh --runtime"
fi
# Each library's package (merged /usr: dpkg may know the path with or without /usr).
packages="$(awk '$2 == "=>" { print $3 }' <<<"$libs" | while read -r lib; do
    real="$(chroot "$root" readlink -f "$lib")"
    chroot "$root" dpkg -S "$real" 2>/dev/null ||
        chroot "$root" dpkg -S "${real#/usr}" 2>/dev/null || echo "?: $real"
done | cut -d: -f1 | sort -u | tr '\n' ' ')"
echo "strata-server's libraries all resolve; they come from: $packages"
[ "$(stat -c %u:%g "$root$RT_VOLUME")" = "$RT_UID:$RT_GID" ] ||
    fail "$RT_VOLUME is not owned by $RT_USER"
chroot --userspec="$RT_USER" "$root" test -w "$RT_VOLUME" ||
    fail "$RT_VOLUME is not writable by $RT_USER"
[ "$(chroot "$root" id -u strata)" = "$RT_UID" ] || fail "user strata is not uid $RT_UID"

# ---- 4. run ----
step "strata-server as the image runs it"
port="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0))
print(s.getsockname()[1])')"
token="$(head -c 24 /dev/urandom | od -An -tx1 | tr -d ' \n')"
mkdir -p "$root/run/secrets"
printf '%s\n' "$token" >"$root/run/secrets/strata_token"
chown "$RT_UID:$RT_GID" "$root/run/secrets/strata_token"
chmod 0400 "$root/run/secrets/strata_token"

# Runs the image's ENTRYPOINT with the image's ENV plus "$@" (NAME=value) and STRATA_PORT=$port,
# as PID 1 of a new PID namespace with /proc, /dev and a read-only /sys, like a container. Sets
# server_pid (the host's pid of the server) and ns_pid (the unshare process to wait for).
start_server() {
    local log="$1"
    shift
    # shellcheck disable=SC2016 # expanded by the inner bash
    unshare --mount --pid --fork --mount-proc="$root/proc" -- bash -euc '
        root=$1 user=$2 workdir=$3 volume=$4
        shift 4
        mount --rbind /dev "$root/dev"
        mount -t sysfs -o ro sysfs "$root/sys"
        # A read-only root with a writable volume, as docker run --read-only gives.
        mount --bind "$root$volume" "$root$volume"
        mount --rbind "$root" "$root"
        mount -o remount,bind,ro "$root"
        exec chroot --userspec="$user" "$root" /usr/bin/env -i --chdir="$workdir" "$@"' \
        _ "$root" "$RT_USER" "$RT_WORKDIR" "$RT_VOLUME" "${RT_ENV[@]}" "$@" "STRATA_PORT=$port" \
        "${RT_ENTRYPOINT[@]}" >"$logs/$log" 2>&1 &
    ns_pid=$!
    pids+=("$ns_pid")
    server_pid=""
    local i
    for ((i = 0; i < 200; i++)); do
        # The server once the chain unshare -> bash -> chroot -> env has exec'd into it.
        server_pid="$(cat "/proc/$ns_pid/task/$ns_pid/children" 2>/dev/null || true)"
        server_pid="${server_pid%% *}"
        # Same file, not same path text: run inside a chroot, /proc/PID/exe names the path as
        # seen from the real root, which is not "$root..." here.
        if [ -n "$server_pid" ] && [ "/proc/$server_pid/exe" -ef \
            "$root$RT_PREFIX/bin/strata-server" ]; then
            pids+=("$server_pid")
            return 0
        fi
        server_pid=""
        kill -0 "$ns_pid" 2>/dev/null || return 0
        sleep 0.05
    done
}

# Waits up to 30 s for the unshare process, which exits with the server's status; sets
# exit_status (-1: still running after 30 s; it is killed).
wait_server() {
    local i
    for ((i = 0; i < 300; i++)); do
        kill -0 "$ns_pid" 2>/dev/null || break
        sleep 0.1
    done
    if kill -0 "$ns_pid" 2>/dev/null; then
        kill -KILL "$server_pid" "$ns_pid" 2>/dev/null || true
        wait "$ns_pid" || true
        pids=()
        exit_status=-1
        return
    fi
    exit_status=0
    wait "$ns_pid" || exit_status=$?
    pids=()  # both gone: never signal their pids again
}

# The image's HEALTHCHECK command, inside the root as USER with the ENV; prints its exit status.
healthcheck() {
    local status=0
    chroot --userspec="$RT_USER" "$root" /usr/bin/env -i "${RT_ENV[@]}" "STRATA_PORT=$port" \
        "${RT_HEALTHCHECK[@]}" >>"$logs/healthcheck.log" 2>&1 || status=$?
    echo "$status"
}

# GET path on the server from this machine; optional bearer token. Prints the status (0: none).
http_status() {
    local path="$1" auth="" fd line
    if [ -n "${2:-}" ]; then auth="Authorization: Bearer $2"$'\r\n'; fi
    if ! { exec {fd}<>"/dev/tcp/127.0.0.1/$port"; } 2>/dev/null; then
        echo 0
        return
    fi
    printf 'GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\n%sConnection: close\r\n\r\n' "$path" "$auth" \
        >&"$fd"
    IFS=' ' read -r -t 10 _ line _ <&"$fd" || line=0
    exec {fd}<&-
    echo "${line:-0}"
}

expect() {
    local what="$1" want="$2" got="$3" log="$4"
    if [ "$got" != "$want" ]; then
        echo "--- $logs/$log:" >&2
        cat "$logs/$log" >&2 || true
        fail "$what: expected $want, got $got"
    fi
    echo "  ok: $what ($got)"
}

wait_healthy() {
    local i
    for ((i = 0; i < 100; i++)); do
        [ "$(healthcheck)" = 0 ] && return 0
        kill -0 "$ns_pid" 2>/dev/null || return 1
        sleep 0.1
    done
    return 1
}

echo "scenario: no token"
start_server no-token.log
wait_server
expect "exit status without a token" 2 "$exit_status" no-token.log
grep -q "without a token" "$logs/no-token.log" || fail "no reason given for refusing to start"

for source in file env; do
    log="token-$source.log"
    if [ $source = file ]; then
        echo "scenario: token in a mounted file (STRATA_TOKEN_FILE), demo scene"
        start_server "$log" STRATA_TOKEN_FILE=/run/secrets/strata_token STRATA_DEMO=1
    else
        echo "scenario: token in STRATA_TOKEN, demo scene"
        start_server "$log" "STRATA_TOKEN=$token" STRATA_DEMO=1
    fi
    [ -n "$server_pid" ] || fail "the server did not start (see $logs/$log)"
    status_file="/proc/$server_pid/status"
    expect "pid inside the namespace" 1 "$(awk '/^NSpid:/ { print $NF }' "$status_file")" "$log"
    expect "uid" "$RT_UID" "$(awk '/^Uid:/ { print $2 }' "$status_file")" "$log"
    expect "capabilities" 0000000000000000 "$(awk '/^CapEff:/ { print $2 }' "$status_file")" "$log"
    wait_healthy || fail "HEALTHCHECK never passed (see $logs/$log, $logs/healthcheck.log)"
    echo "  ok: HEALTHCHECK ${RT_HEALTHCHECK[*]} exits 0"
    expect "GET /readyz without a token" 200 "$(http_status /readyz)" "$log"
    expect "GET /v1/stats without a token" 401 "$(http_status /v1/stats)" "$log"
    expect "GET /v1/stats with a wrong token" 401 "$(http_status /v1/stats "x$token")" "$log"
    expect "GET /v1/stats with the token" 200 "$(http_status /v1/stats "$token")" "$log"
    expect "GET /v1/render (64x64 PNG) with the token" 200 \
        "$(http_status '/v1/render?width=64&height=64' "$token")" "$log"
    kill -TERM "$server_pid"
    wait_server
    expect "exit status after SIGTERM to PID 1" 0 "$exit_status" "$log"
    expect "HEALTHCHECK once stopped" 1 "$(healthcheck)" "$log"
    if grep -qF "$token" "$logs/$log"; then fail "the token appears in the server's log"; fi
done

echo "scenario: STRATA_INSECURE=1, no token"
start_server insecure.log STRATA_INSECURE=1
[ -n "$server_pid" ] || fail "the server did not start (see $logs/insecure.log)"
wait_healthy || fail "HEALTHCHECK never passed (see $logs/insecure.log)"
expect "GET /v1/stats without a token" 200 "$(http_status /v1/stats)" insecure.log
kill -INT "$server_pid"
wait_server
expect "exit status after SIGINT to PID 1" 0 "$exit_status" insecure.log

step "docker checks passed in $((SECONDS - started)) s"
