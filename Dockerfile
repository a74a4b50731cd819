# rcsa REST service: tool-point FRFs by receptance coupling.
#
#   docker build -t rcsa .
#   docker run -p 127.0.0.1:8000:8000 -v rcsa-store:/data --read-only --tmpfs /tmp rcsa
#   docker run --rm -v rcsa-store:/data rcsa rcsa keys create --scope write   # prints a key once
#
# The store (measurements, jobs, libraries, hashed API keys) is /data/store: mount a named volume
# (or a host directory writable by uid 10001) on /data, or it is lost with the container — the
# image declares no VOLUME, so nothing is created behind your back. The service runs as the
# unprivileged user rcsa (uid 10001) with RCSA_WORKERS uvicorn workers (default 2) sharing the
# store safely; it writes nothing outside /data and /tmp, so the root file system may be
# read-only. Slow clients are bounded (RCSA_HEADER_TIMEOUT_S, RCSA_BODY_TIMEOUT_S with
# RCSA_BODY_MIN_RATE_BYTES_S, RCSA_TIMEOUT_KEEP_ALIVE_S) and so are connections
# (RCSA_LIMIT_CONCURRENCY per worker: 503 beyond). A start that cannot work (bad RCSA_*
# setting, store not writable, Dask scheduler unreachable) exits 1 with the reason.
# docker-compose.yml runs it with a Dask scheduler and two workers (RCSA_EXTRAS=dask).
#
# Base image: BASE_IMAGE defaults to the upstream python:3.11.11-slim-bookworm pinned by its
# digest. Where no registry can be reached, docker/build-base.sh makes a local stand-in from
# Debian packages: docker build --build-arg BASE_IMAGE=rcsa-base:bookworm-python3.11 -t rcsa .
#
# Layers: the dependencies (pyproject.toml's requirements, pinned by constraints.txt) are
# installed before the code is copied, so a code change (or an edit of pyproject.toml that
# leaves its requirements alone) rebuilds only the last, small layer.
ARG BASE_IMAGE=python:3.11.11-slim-bookworm@sha256:081075da77b2b55c23c088251026fb69a7b2bf92471e491ff5fd75c192fd38e5

# 0. the requirements alone, out of pyproject.toml: the dependency layer below is keyed on this
#    list (and constraints.txt), not on the whole pyproject.toml, so editing the tools'
#    configuration there (ruff, pytest, import-linter) does not reinstall the dependencies
FROM ${BASE_IMAGE} AS requirements
# extras to install, e.g. --build-arg RCSA_EXTRAS=dask for a Dask cluster (docker-compose.yml)
ARG RCSA_EXTRAS=""
COPY pyproject.toml docker/requirements.py /r/
RUN python3 /r/requirements.py /r/pyproject.toml "$RCSA_EXTRAS" > /r/requirements.txt

FROM ${BASE_IMAGE}
ENV PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PATH=/opt/venv/bin:$PATH \
    RCSA_STORE=/data/store \
    RCSA_WORKERS=2 \
    RCSA_LIMIT_CONCURRENCY=100 \
    RCSA_TIMEOUT_KEEP_ALIVE_S=5 \
    RCSA_MAX_HEAD_BYTES=16384 \
    RCSA_HEADER_TIMEOUT_S=10 \
    RCSA_BODY_TIMEOUT_S=10 \
    RCSA_BODY_MIN_RATE_BYTES_S=4096 \
    MPLCONFIGDIR=/tmp/matplotlib

RUN useradd --uid 10001 --user-group --no-create-home --home-dir /tmp --shell /usr/sbin/nologin rcsa \
    && mkdir -p /data \
    && chown rcsa:rcsa /data \
    && python3 -m venv /opt/venv \
    && pip uninstall -q -y setuptools

# 1. the dependencies: rebuilt only when the requirements or constraints.txt change. The
#    packages' own test suites (tests/ and test/ directories: 53 MB, 65 MB with dask; never
#    imported) are removed in the same layer.
COPY --from=requirements /r/requirements.txt /src/
COPY constraints.txt /src/
RUN pip install -c /src/constraints.txt -r /src/requirements.txt hatchling \
    && find /opt/venv/lib/python3*/site-packages -mindepth 2 -type d \( -name tests -o -name test \) \
         -prune -exec rm -rf {} +

# 2. the code: rcsa and the service, built with the hatchling of layer 1 (no download)
COPY pyproject.toml README.md /src/
COPY src /src/src
COPY service /src/service
RUN pip install --no-deps --no-build-isolation /src \
    && rm -rf /src

USER rcsa
WORKDIR /tmp
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=60s --retries=3 \
    CMD python3 -c "import sys, urllib.request; sys.exit(urllib.request.urlopen('http://127.0.0.1:8000/readyz', timeout=4).status != 200)"
# rcsa serve checks the settings, the store and the Dask scheduler once before it starts the
# workers (exit 1 with the reason), then runs uvicorn with the service's HTTP protocol.
CMD ["sh", "-c", "exec rcsa serve --host 0.0.0.0 --port 8000 --workers \"$RCSA_WORKERS\""]
