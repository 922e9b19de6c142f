#!/usr/bin/env bash
# Builds the server image (docker/Dockerfile), runs it, waits for its health check, calls it
# from the host CLI, scrapes /metrics, fetches the viewer and one gRPC-Web call from its HTTP
# port, stops it with SIGTERM and checks that it exited 0.
#
# Uses docker when an engine answers; otherwise podman (installed here if missing, as root)
# with the two settings these machines need (docker/containers.conf) and a Debian bookworm
# base image debootstrapped from the machine's own mirror, since no image registry is
# reachable. Not part of scripts/test: the image build compiles and tests the whole project
# (docs/operations.md has the timings). Exit 0 when every check passed.
#
# Environment: SPORTSIM_IMAGE (localhost/sportsim:latest), SMOKE_GRPC_PORT (50061),
# SMOKE_METRICS_PORT (9474), SMOKE_HTTP_PORT (8088), SMOKE_MAX_IMAGE_MB (150),
# SMOKE_BASE_IMAGE (podman's local base image, localhost/bookworm:base; made when missing),
# SMOKE_REBASE=1 to make the base image again, SMOKE_COMPOSE=1 to also run docker/compose.yaml
# (with podman-compose or docker compose, when one is installed), SMOKE_BUILD_CA (a CA bundle
# for the build stage's npm ci; podman: the host's /etc/ssl/certs/ca-certificates.crt). The
# host CLI is built in SPORTSIM_BUILD_DIR (build/), as scripts/lib.sh does.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
image=${SPORTSIM_IMAGE:-localhost/sportsim:latest}
grpc_port=${SMOKE_GRPC_PORT:-50061}
metrics_port=${SMOKE_METRICS_PORT:-9474}
http_port=${SMOKE_HTTP_PORT:-8088}
max_mb=${SMOKE_MAX_IMAGE_MB:-150}
name=sportsim-smoke-$$
start=$(date +%s)
base_rootfs=""   # make_base's debootstrap tree while it exists; removed on exit

# Progress and failures go to stderr, so they show even where stdout is captured.
say() { printf '[smoke %4ss] %s\n' "$(($(date +%s) - start))" "$*" >&2; }
fail() { say "FAIL: $*"; exit 1; }

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else
    fail "need root for: $*"
  fi
}

# A bookworm base image from the mirror this machine's apt uses: minbase, the same sources, no
# package caches, no recommends, and no docs, man pages or translations, now or from packages
# installed later (what debian:bookworm-slim does; it saves ~45 MB).
# The tree lives in the global base_rootfs, which the EXIT trap removes if make_base fails
# half-way. (Not a RETURN trap: bash keeps a RETURN trap set in a function after it returns and
# runs it after every later `source`, where the function's locals no longer exist.)
make_base() {
  local rootfs sources mirror
  sources=/etc/apt/sources.list.d/debian.sources
  mirror=$(awk '/^URIs:/ {print $2; exit}' "$sources" 2>/dev/null || true)
  mirror=${mirror:-http://deb.debian.org/debian}
  rootfs=$(mktemp -d /var/tmp/sportsim-bookworm.XXXXXX)
  base_rootfs=$rootfs
  say "debootstrap bookworm (minbase) from $mirror"
  as_root debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >/dev/null
  if [ -f "$sources" ]; then
    as_root cp "$sources" "$rootfs/etc/apt/sources.list.d/debian.sources"
    as_root rm -f "$rootfs/etc/apt/sources.list"
  fi
  as_root sh -c "cat > '$rootfs/etc/apt/apt.conf.d/90sportsim-slim'" <<'CONF'
Dir::Cache::pkgcache "";
Dir::Cache::srcpkgcache "";
APT::Install-Recommends "false";
APT::Install-Suggests "false";
CONF
  as_root sh -c "cat > '$rootfs/etc/dpkg/dpkg.cfg.d/90sportsim-slim'" <<'CONF'
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/man/*
path-exclude /usr/share/info/*
path-exclude /usr/share/locale/*
path-include /usr/share/locale/locale.alias
path-exclude /usr/share/lintian/*
CONF
  as_root find "$rootfs/usr/share/doc" -mindepth 1 -not -name copyright -not -type d -delete
  as_root rm -rf "$rootfs"/usr/share/man/* "$rootfs"/usr/share/info/* "$rootfs"/usr/share/lintian/*
  as_root find "$rootfs/usr/share/locale" -mindepth 1 -maxdepth 1 -not -name locale.alias \
    -exec rm -rf {} +
  as_root rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/*
  as_root tar --numeric-owner -C "$rootfs" -c . | podman import - "$base" >/dev/null
  as_root rm -rf "$rootfs"
  base_rootfs=""
}

cleanup() {
  if [ -n "${engine:-}" ]; then "$engine" rm -f "$name" >/dev/null 2>&1 || true; fi
  rm -f "${TMPDIR:-/tmp}/$name.run.log"
  if [ -n "$base_rootfs" ]; then as_root rm -rf "$base_rootfs" || true; fi
}
trap cleanup EXIT

if command -v docker >/dev/null && docker info >/dev/null 2>&1; then
  engine=docker
  base=debian:bookworm-slim
else
  engine=podman
  if ! command -v podman >/dev/null || ! command -v runc >/dev/null ||
     ! command -v debootstrap >/dev/null; then
    say "installing podman, runc and debootstrap"
    as_root apt-get -o DPkg::Lock::Timeout=900 update >/dev/null
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
      podman runc debootstrap >/dev/null
  fi
  export CONTAINERS_CONF=$root/docker/containers.conf
  base=${SMOKE_BASE_IMAGE:-localhost/bookworm:base}
  # SMOKE_REBASE=1 makes the base image again (e.g. after a change to make_base).
  if [ "${SMOKE_REBASE:-0}" = 1 ]; then podman rmi -f "$base" >/dev/null 2>&1 || true; fi
  podman image exists "$base" || make_base
fi
say "engine: $engine, base: $base"

say "building $image (build stage: scripts/setup, Release build, whole test suite)"
build_start=$(date +%s)
format=()
# podman writes OCI images by default, which have no HEALTHCHECK: ask for the docker format.
[ "$engine" = podman ] && format=(--format docker)
# The build stage's viewer test runs headless Chromium, which wants more than the default 64 MB
# of /dev/shm.
# npm ci in the build stage trusts what this host trusts (a TLS-re-signing proxy's CA, say): the
# host's CA bundle goes in as the secret build_ca, read by that step only. SMOKE_BUILD_CA names
# another bundle; on docker it is passed only when set (--secret needs BuildKit).
secret=()
build_ca=${SMOKE_BUILD_CA:-}
if [ -z "$build_ca" ] && [ "$engine" = podman ] && [ -s /etc/ssl/certs/ca-certificates.crt ]; then
  build_ca=/etc/ssl/certs/ca-certificates.crt
fi
[ -n "$build_ca" ] && secret=(--secret "id=build_ca,src=$build_ca")
"$engine" build "${format[@]}" "${secret[@]}" --shm-size 1g -f "$root/docker/Dockerfile" \
  --build-arg "BASE=$base" -t "$image" "$root"
build_s=$(($(date +%s) - build_start))
say "image built in ${build_s}s"

size=$("$engine" image inspect --format '{{.Size}}' "$image")
size_mb=$((size / 1000000))
say "runtime image: ${size_mb} MB (limit ${max_mb} MB)"
[ "$size_mb" -le "$max_mb" ] || fail "image is ${size_mb} MB, over ${max_mb} MB"

# The host CLI, built the README's way (configure and build in build/).
"$root/scripts/setup"
# shellcheck source=../scripts/lib.sh
source "$root/scripts/lib.sh"
configure
cmake --build "$build_dir" --target sportsim >/dev/null
cli=("$build_dir/bin/sportsim" --server "127.0.0.1:$grpc_port")

say "starting $name on 127.0.0.1:$grpc_port (gRPC), 127.0.0.1:$metrics_port (metrics)" \
  "and 127.0.0.1:$http_port (HTTP: viewer and gRPC-Web)"
# (podman without systemd logs that it cannot schedule health-check timers; the checks below
# run the HEALTHCHECK command themselves, so that noise is kept out of the output.)
"$engine" run -d --name "$name" -p "127.0.0.1:$grpc_port:50051" \
  -p "127.0.0.1:$metrics_port:9464" -p "127.0.0.1:$http_port:8080" "$image" >/dev/null 2>"${TMPDIR:-/tmp}/$name.run.log" ||
  { cat "${TMPDIR:-/tmp}/$name.run.log"; fail "cannot start the container"; }

user=$("$engine" exec "$name" id -u)
[ "$user" != 0 ] || fail "the server runs as root"
say "server runs as uid $user"

healthy=""
for _ in $(seq 1 60); do
  if [ "$engine" = podman ]; then
    # podman runs the image's HEALTHCHECK command on demand (no systemd timers here).
    if podman healthcheck run "$name" >/dev/null 2>&1; then healthy=1; break; fi
  else
    status=$(docker inspect --format '{{.State.Health.Status}}' "$name")
    if [ "$status" = healthy ]; then healthy=1; break; fi
  fi
  [ "$("$engine" inspect --format '{{.State.Running}}' "$name")" = true ] ||
    { "$engine" logs "$name" || true; fail "the server exited while starting"; }
  sleep 1
done
[ -n "$healthy" ] || { "$engine" logs "$name" || true; fail "not healthy within 60 s"; }
say "HEALTHCHECK passes"

# Each output is captured whole before it is checked: `cli | grep -q` would let grep exit at
# its first match and the CLI die of SIGPIPE, which pipefail reports as a failure.
expect() {  # expect WHAT PATTERN CLI-ARGS...: run the host CLI, and require PATTERN in its output
  local what=$1 pattern=$2 out
  shift 2
  out=$("${cli[@]}" "$@" 2>&1) || { echo "$out" | tail -5 >&2; fail "host '$what' failed"; }
  grep -q -- "$pattern" <<<"$out" || { echo "$out" | head -5 >&2; fail "host '$what': no $pattern"; }
  printf '%s' "$out"
}
expect health SERVING health >/dev/null
expect info '"version"' --format json info >/dev/null
expect "shot simulate" '"t_rest_s"' --format json shot simulate --table pool-9ft --rack 8ball \
  --ball-speed 8 >/dev/null
expect "swing simulate" '"carry_m"' --format json swing simulate --integrator rk4 --dt 0.0025 \
  --club driver >/dev/null
expect "table create" '"table_id"' --format json table create --table pool-9ft --rack 8ball \
  >/dev/null
say "host CLI: health, info, shot simulate, swing simulate --club driver, table create: ok"

metrics=$(curl -fsS "http://127.0.0.1:$metrics_port/metrics") || fail "/metrics not reachable"
grep -q '^sportsim_worlds{world="table"} 1' <<<"$metrics" ||
  fail "/metrics does not show the table just created"
grep -q 'sportsim_rpcs_total{.*method="/sportsim.v1.Billiards/SimulateShot"' <<<"$metrics" ||
  fail "/metrics does not count the SimulateShot call"
say "/metrics: the table and the RPCs are counted"

page=$(curl -fsS "http://127.0.0.1:$http_port/") || fail "the viewer (/) not reachable"
grep -q '<title>sportsim viewer</title>' <<<"$page" || { echo "$page" | head -5 >&2;
                                                        fail "/ is not the viewer's index.html"; }
curl -fsS -o /dev/null "http://127.0.0.1:$http_port/app.js" || fail "/app.js not reachable"
# One gRPC-Web call in the text encoding: an empty GetInfoRequest is the 5-byte frame header
# 00 00000000, base64 "AAAAAAA="; the reply is base64 frames, the last one the trailers.
reply=$(curl -fsS -X POST -H 'content-type: application/grpc-web-text' \
  -H 'accept: application/grpc-web-text' -H 'x-grpc-web: 1' --data-binary 'AAAAAAA=' \
  "http://127.0.0.1:$http_port/sportsim.v1.Server/GetInfo") || fail "gRPC-Web GetInfo failed"
# (Frames are base64-encoded one by one, so decode each padded chunk on its own.)
decoded=$(grep -o '[A-Za-z0-9+/]*=*' <<<"$reply" | while read -r chunk; do
            base64 -d <<<"$chunk" 2>/dev/null || true; done | tr -c '[:print:]\n' ' ')
grep -q 'grpc-status: *0' <<<"$decoded" && grep -q 'Release' <<<"$decoded" ||
  { printf '%s\n' "$decoded" | head -c 600 >&2; fail "gRPC-Web GetInfo: no OK status or no info"; }
say "HTTP: the viewer at / and gRPC-Web GetInfo (grpc-status 0) answer"

say "stopping with SIGTERM"
"$engine" stop -t 15 "$name" >/dev/null
code=$("$engine" inspect --format '{{.State.ExitCode}}' "$name")
logs=$("$engine" logs "$name" 2>&1)
grep -q "SIGTERM, draining" <<<"$logs" || { echo "$logs"; fail "no SIGTERM drain in the logs"; }
[ "$code" = 0 ] || { echo "$logs"; fail "exit code $code after SIGTERM"; }
say "SIGTERM: drained and exited 0"

if [ "${SMOKE_COMPOSE:-0}" = 1 ]; then
  if [ "$engine" = podman ]; then
    # podman-compose, and the CNI dnsname plugin so the client can resolve "server".
    if ! command -v podman-compose >/dev/null ||
       [ ! -e /usr/lib/cni/dnsname ]; then
      say "installing podman-compose and the CNI dnsname plugin"
      as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
        podman-compose golang-github-containernetworking-plugin-dnsname >/dev/null
    fi
    compose=(podman-compose -f "$root/docker/compose.yaml")
  elif docker compose version >/dev/null 2>&1; then
    compose=(docker compose -f "$root/docker/compose.yaml")
  else
    fail "SMOKE_COMPOSE=1 needs docker compose with a docker engine"
  fi
  say "compose: the server, then the one-shot client against it"
  compose_down() { "${compose[@]}" down >/dev/null 2>&1 || true; }
  compose_down
  "${compose[@]}" up -d --no-build server >/dev/null 2>&1 || { compose_down; fail "compose up"; }
  # (podman-compose 1.0 has no --exit-code-from; `run` returns the client's status.)
  out=$("${compose[@]}" run --rm client 2>&1) || { echo "$out" | tail -20 >&2; compose_down;
                                                   fail "the compose client failed"; }
  compose_down
  grep -q '"version"' <<<"$out" && grep -qi 'at rest' <<<"$out" ||
    { echo "$out" | tail -20 >&2; fail "the compose client's output lacks info or the shot"; }
  say "compose: the client ran info and shot simulate against the server"
fi

say "PASS (image build ${build_s}s, total $(($(date +%s) - start))s)"
