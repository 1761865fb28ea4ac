#!/usr/bin/env bash
# A throwaway PostgreSQL server for a league's store (tests, CI, trying a
# multi-host league on one machine).
#
#   scripts/postgres.sh start DIR   initialise a cluster in DIR (once), start
#                                   it on a free local port, print its URL as
#                                   the last line
#   scripts/postgres.sh stop DIR    shut that cluster down
#   scripts/postgres.sh url DIR     print the URL of the cluster in DIR
#
# start installs PostgreSQL from the distribution's packages if it is
# missing. The server runs as an unprivileged user (postgres refuses root):
# when run as root, the system user t2e-postgres (created if missing) owns
# DIR. A restart (stop, then start) keeps the cluster's port and password.
set -euo pipefail

usage() { echo "usage: $0 start|stop|url DIR" >&2; exit 2; }
[ $# -eq 2 ] || usage
cmd=$1
mkdir -p "$2"
dir=$(cd "$2" && pwd)
data=$dir/data

find_bin() {
    local d
    for d in /usr/lib/postgresql/*/bin; do
        [ -x "$d/pg_ctl" ] && [ -x "$d/initdb" ] && { echo "$d"; return 0; }
    done
    if command -v pg_ctl >/dev/null && command -v initdb >/dev/null; then
        dirname "$(command -v pg_ctl)"
        return 0
    fi
    return 1
}

install_postgres() {
    echo "PostgreSQL's server is not installed; installing it from the distribution's packages" >&2
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends postgresql >&2 ||
        { $sudo apt-get update >&2 && $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends postgresql >&2; }
}

# Runs a command as the cluster's owner.
as_owner() {
    if [ "$(id -u)" -eq 0 ]; then
        runuser -u t2e-postgres -- "$@"
    else
        "$@"
    fi
}

url() {
    echo "postgres://t2e:$(cat "$dir/password")@127.0.0.1:$(cat "$dir/port")/t2e"
}

case "$cmd" in
start)
    bin=$(find_bin) || { install_postgres; bin=$(find_bin) || { echo "$0: PostgreSQL's server is still missing after installing it" >&2; exit 1; }; }
    if [ "$(id -u)" -eq 0 ]; then
        id -u t2e-postgres >/dev/null 2>&1 ||
            useradd --system --no-create-home --home-dir /nonexistent --shell /usr/sbin/nologin t2e-postgres
        chown t2e-postgres "$dir"
    fi
    if [ ! -f "$data/PG_VERSION" ]; then
        rm -rf "$data"
        head -c 18 /dev/urandom | base64 | tr -d '/+=' > "$dir/password"
        chmod 600 "$dir/password"
        [ "$(id -u)" -eq 0 ] && chown t2e-postgres "$dir/password"
        python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])' > "$dir/port"
        as_owner "$bin/initdb" -D "$data" -U t2e --pwfile="$dir/password" \
            --auth-local=scram-sha-256 --auth-host=scram-sha-256 -E UTF8 --locale=C.UTF-8 >"$dir/initdb.log" 2>&1 ||
            as_owner "$bin/initdb" -D "$data" -U t2e --pwfile="$dir/password" \
                --auth-local=scram-sha-256 --auth-host=scram-sha-256 -E UTF8 --no-locale >"$dir/initdb.log" 2>&1 ||
            { cat "$dir/initdb.log" >&2; exit 1; }
        mkdir -p "$dir/socket"
        [ "$(id -u)" -eq 0 ] && chown t2e-postgres "$dir/socket"
        {
            echo "listen_addresses = '127.0.0.1'"
            echo "port = $(cat "$dir/port")"
            echo "unix_socket_directories = '$dir/socket'"
            echo "max_connections = 200"
            echo "fsync = on"
        } >> "$data/postgresql.conf"
    fi
    if ! as_owner "$bin/pg_ctl" -D "$data" status >/dev/null 2>&1; then
        as_owner "$bin/pg_ctl" -D "$data" -l "$dir/server.log" -w -t 60 start >&2 ||
            { tail -20 "$dir/server.log" >&2; exit 1; }
    fi
    if ! PGPASSWORD=$(cat "$dir/password") "$bin/psql" -h 127.0.0.1 -p "$(cat "$dir/port")" -U t2e -d postgres -tAc \
        "SELECT 1 FROM pg_database WHERE datname = 't2e'" | grep -q 1; then
        PGPASSWORD=$(cat "$dir/password") "$bin/psql" -h 127.0.0.1 -p "$(cat "$dir/port")" -U t2e -d postgres -qc "CREATE DATABASE t2e" >&2
    fi
    url
    ;;
stop)
    bin=$(find_bin) || { echo "$0: PostgreSQL is not installed" >&2; exit 1; }
    if [ -f "$data/PG_VERSION" ] && as_owner "$bin/pg_ctl" -D "$data" status >/dev/null 2>&1; then
        as_owner "$bin/pg_ctl" -D "$data" -m fast -w stop >&2
    fi
    ;;
url)
    [ -f "$dir/port" ] || { echo "$0: $dir holds no cluster; start one" >&2; exit 1; }
    url
    ;;
*)
    usage
    ;;
esac
