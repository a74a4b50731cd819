#!/usr/bin/env bash
# Smoke test of the Docker image and the compose deployment on a real Docker engine.
#
#   docker/smoke.sh                                              # base image from a registry
#   BASE_IMAGE=rcsa-base:bookworm-python3.11 docker/smoke.sh     # the local base (docker/build-base.sh)
#
# 1. builds the image (rcsa:smoke) and reports its size and build time;
# 2. a start that cannot work exits 1 with the reason: a bad RCSA_* setting, a store the
#    service cannot write, a Dask scheduler nobody runs;
# 3. starts it as a user would (read-only root, /tmp in memory, a named volume on /data, port
#    published on 127.0.0.1 only) and checks: /healthz, the container's health turning
#    "healthy", uid 10001 (not root), the root file system refusing writes, an RA-1 prediction
#    (first natural frequency 599.85 Hz), a measurement upload that is still there after
#    `docker restart` and after the container is replaced by a new one on the same volume;
# 4. compose: builds rcsa:dask once, starts the service, a Dask scheduler and two workers,
#    runs a library sync as a job and checks that the Dask workers computed it, then
#    `docker compose down -v` and checks that the store volume is still there.
#
# Needs docker (and `docker compose` or docker-compose), curl and python3. Uses only its own
# names (rcsa:smoke, rcsa:dask, volumes and containers rcsa-smoke-*, compose project
# rcsa-smoke) and removes its containers and volumes at the end. Ports: SMOKE_PORT (18000)
# and SMOKE_PORT+1. Exit status 0 when every check passed.
set -euo pipefail
cd "$(dirname "$0")/.."

port=${SMOKE_PORT:-18000}
compose_port=$((port + 1))
image=rcsa:smoke
tag=rcsa-smoke-$$
volume=$tag-store
compose_volume=$tag-compose-store
key="smoke-$(od -An -N12 -tx1 /dev/urandom | tr -d ' \n')"
build_args=()
[ -n "${BASE_IMAGE:-}" ] && build_args=(--build-arg "BASE_IMAGE=$BASE_IMAGE")
if docker compose version >/dev/null 2>&1; then compose=(docker compose); else compose=(docker-compose); fi
compose+=(-p rcsa-smoke)
export RCSA_BASE_IMAGE=${BASE_IMAGE:-python:3.11.11-slim-bookworm@sha256:081075da77b2b55c23c088251026fb69a7b2bf92471e491ff5fd75c192fd38e5}
export RCSA_STORE_VOLUME=$compose_volume RCSA_PORT=$compose_port

failures=0
pass() { echo "PASS  $*"; }
fail() { echo "FAIL  $*"; failures=$((failures + 1)); }
check() { local what=$1; shift; if "$@"; then pass "$what"; else fail "$what"; fi; }
json() { python3 -c "import json, sys; d = json.load(sys.stdin); print($1)"; }

cleanup() {
    docker rm -f "$tag" "$tag-2" >/dev/null 2>&1 || true
    "${compose[@]}" down >/dev/null 2>&1 || true
    docker volume rm "$volume" "$compose_volume" >/dev/null 2>&1 || true
    [ -n "${unwritable:-}" ] && rm -rf "$unwritable"
}
trap cleanup EXIT

wait_http() {  # URL: until it answers 200 (counted attempts, 0.5 s apart; a dead container stops it)
    local url=$1 container=${2:-}
    for _ in $(seq 1 240); do
        curl -sf -o /dev/null "$url" && return 0
        if [ -n "$container" ] && [ "$(docker inspect -f '{{.State.Running}}' "$container" 2>/dev/null)" != true ]; then
            docker logs "$container" 2>&1 | tail -20 >&2
            return 1
        fi
        sleep 0.5
    done
    return 1
}

# ----------------------------------------------------------------------------------- 1. build
t0=$SECONDS
docker build -q "${build_args[@]}" -t "$image" . >/dev/null
build_s=$((SECONDS - t0))
size=$(docker image inspect -f '{{.Size}}' "$image" | awk '{printf "%.0f MB", $1 / 1e6}')
echo "image $image: built in ${build_s} s, $size (base: ${BASE_IMAGE:-the Dockerfile default})"

# ------------------------------------------------------------------------ 2. failing starts
expect_exit_1() {  # WHAT PATTERN DOCKER-RUN-ARGS...: exit status 1 and the reason on stderr
    local what=$1 pattern=$2 out status
    shift 2
    set +e
    out=$(docker run --rm --read-only --tmpfs /tmp "$@" 2>&1)
    status=$?
    set -e
    if [ "$status" -eq 1 ] && grep -q -- "$pattern" <<<"$out"; then
        pass "$what: exit 1, '$(grep -m1 -- "$pattern" <<<"$out" | cut -c1-150)'"
    else
        fail "$what: exit $status: $(tail -3 <<<"$out")"
    fi
}
expect_exit_1 "bad setting RCSA_MAX_BODY_BYTES=abc" "RCSA_MAX_BODY_BYTES" -e RCSA_MAX_BODY_BYTES=abc "$image"
unwritable=$(mktemp -d)   # owned by this (host) user, mode 700: uid 10001 cannot write it
expect_exit_1 "store not writable (a root-owned directory on /data)" "cannot start" -v "$unwritable:/data" "$image"

# ------------------------------------------------------------------------------- 3. one container
docker volume create "$volume" >/dev/null
run_service() {  # NAME
    docker run -d --name "$1" --read-only --tmpfs /tmp -p "127.0.0.1:$port:8000" -v "$volume:/data" \
        -e RCSA_API_KEYS="$key:write" --health-interval 2s --health-start-period 60s "$image" >/dev/null
}
t0=$SECONDS
run_service "$tag"
base="http://127.0.0.1:$port"
check "/healthz answers 200" wait_http "$base/healthz" "$tag"
echo "      ... $((SECONDS - t0)) s after docker run"
healthy=""
for _ in $(seq 1 90); do
    healthy=$(docker inspect -f '{{.State.Health.Status}}' "$tag")
    [ "$healthy" = healthy ] && break
    sleep 1
done
check "container health: $healthy" test "$healthy" = healthy
uid=$(docker exec "$tag" id -u)
check "runs as uid $uid (not root)" test "$uid" = 10001
check "root file system is read-only" bash -c "! docker exec $tag touch /opt/venv/written 2>/dev/null"
published=$(docker port "$tag" 8000/tcp | head -1)
check "published on $published only" test "$published" = "127.0.0.1:$port"

f1=$(curl -sf -X POST -H 'content-type: application/json' --data @examples/ra1.json "$base/v1/tool-point-frf" \
     | json 'd["natural_frequencies_hz"][0]')
check "RA-1 prediction: first natural frequency $f1 Hz" python3 -c "assert abs($f1 - 599.85) < 0.01"

upload=$(curl -sf -X POST -H "X-API-Key: $key" -H 'content-type: application/json' \
         --data @tests/data/measurements/point_receptance.json "$base/v1/measurements")
mid=$(json 'd["id"]' <<<"$upload")
before=$(curl -sf "$base/v1/measurements/$mid" | sha256sum)
check "measurement $mid uploaded" test -n "$mid"
docker restart "$tag" >/dev/null
wait_http "$base/healthz" "$tag"
after=$(curl -sf "$base/v1/measurements/$mid" | sha256sum || true)
check "measurement unchanged after docker restart" test "$before" = "$after"
docker rm -f "$tag" >/dev/null
run_service "$tag-2"
wait_http "$base/healthz" "$tag-2"
after=$(curl -sf "$base/v1/measurements/$mid" | sha256sum || true)
check "measurement unchanged in a new container on the same volume" test "$before" = "$after"
docker rm -f "$tag-2" >/dev/null

# ---------------------------------------------------------------------------------- 4. compose
docker volume create "$compose_volume" >/dev/null
t0=$SECONDS
"${compose[@]}" build >/dev/null
echo "compose build: $((SECONDS - t0)) s, rcsa:dask $(docker image inspect -f '{{.Size}}' rcsa:dask | awk '{printf "%.0f MB", $1 / 1e6}')"
check "compose builds one image: one build: section, four services on rcsa:dask" test "$("${compose[@]}" config | grep -c '^    build:') $("${compose[@]}" config | grep -c 'image: rcsa:dask')" = "1 4"
expect_exit_1 "Dask scheduler unreachable" "cannot reach the Dask scheduler" --tmpfs /data:uid=10001,gid=10001 \
    -e RCSA_DASK_SCHEDULER=tcp://127.0.0.1:9 -e RCSA_DASK_CONNECT_TIMEOUT_S=2 rcsa:dask
"${compose[@]}" up -d
cbase="http://127.0.0.1:$compose_port"
check "compose: service /readyz answers" wait_http "$cbase/readyz"
workers=0
for _ in $(seq 1 120); do  # both workers registered with the scheduler
    workers=$("${compose[@]}" exec -T scheduler python3 -c "
from distributed import Client
with Client('tcp://127.0.0.1:8786', timeout=10) as c:
    print(len(c.nthreads()))" 2>/dev/null || echo 0)
    [ "$workers" = 2 ] && break
    sleep 1
done
check "compose: $workers Dask workers registered" test "$workers" = 2
ckey=$("${compose[@]}" exec -T service rcsa keys create --scope write --label smoke | grep -o 'rcsa_[A-Za-z0-9_-]*' | head -1)
spindle=$(json 'json.dumps(d["spindle"])' <examples/ra1.json)
joints=$(json 'json.dumps(d["joints"])' <examples/ra1.json)
library=$(mktemp --suffix=.json)   # 600 end mills: the synthetic library's first tool, 600 diameters
python3 - tests/data/tool-libraries/fusion-synthetic/synthetic_library.json "$library" <<'PY'
import copy, json, sys
doc = json.load(open(sys.argv[1]))
mill = doc["data"][0]
tools = []
for i in range(600):
    tool = copy.deepcopy(mill)
    tool["guid"] = f"00000000-0000-4000-8000-{i:012d}"
    tool["geometry"]["DC"] = 10.0 + 0.005 * i
    tools.append(tool)
json.dump({"data": tools, "version": doc.get("version", 36)}, open(sys.argv[2], "w"))
PY
t0=$SECONDS
job=$(curl -sf -X POST -H "X-API-Key: $ckey" -H 'Prefer: respond-async' -F "library=@$library" \
      -F "spindle=$spindle" -F "joints=$joints" -F 'frequency={"start_hz": 5, "stop_hz": 5000, "step_hz": 1}' \
      "$cbase/v1/libraries/smoke:sync" -D - -o /dev/null | tr -d '\r' | sed -n 's/^[Ll]ocation: //p')
status=""
for _ in $(seq 1 600); do
    status=$(curl -sf "$cbase$job" | json 'd["status"]')
    case $status in succeeded|failed) break ;; esac
    sleep 0.5
done
check "compose: library sync job $job $status ($((SECONDS - t0)) s)" test "$status" = succeeded
summary=$(curl -sf "$cbase/v1/libraries/smoke" | json 'd.get("last_sync", {}).get("counts")')
echo "      library smoke: $summary"
check "compose: 600 tools added" python3 -c "assert $summary['added'] == 600, $summary"
rm -f "$library"
executed=$("${compose[@]}" exec -T scheduler python3 -c "
from distributed import Client
with Client('tcp://127.0.0.1:8786', timeout=10) as c:
    print(' '.join(str(n) for n in c.run(lambda dask_worker: dask_worker.state.executed_count).values()))")
check "compose: both Dask workers computed chunks (tasks per worker: $executed)" \
    python3 -c "n = [int(x) for x in '$executed'.split()]; assert len(n) == 2 and min(n) >= 1, n"
"${compose[@]}" down -v
check "compose down -v keeps the store volume $compose_volume" docker volume inspect "$compose_volume" >/dev/null

echo "smoke: $failures failure(s)"
[ "$failures" -eq 0 ]
