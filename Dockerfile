# rcsa REST service: tool-point FRFs by receptance coupling.
#
#   docker build -t rcsa .
#   docker run -p 8000:8000 -v rcsa-store:/data rcsa
#   docker run --rm -v rcsa-store:/data rcsa rcsa keys create --scope write   # prints a key once
#
# The store (measurements, jobs, hashed API keys) lives in the volume /data; the service runs
# as an unprivileged user with two uvicorn workers (RCSA_WORKERS) sharing it safely.
# docker-compose.yml builds it with RCSA_EXTRAS=dask and runs it as the service, a Dask
# scheduler and two Dask workers.

FROM python:3.11-slim AS build
# extras to install, e.g. --build-arg RCSA_EXTRAS=dask for a Dask cluster (docker-compose.yml)
ARG RCSA_EXTRAS=""
ENV PIP_NO_CACHE_DIR=1 PIP_DISABLE_PIP_VERSION_CHECK=1
WORKDIR /src
COPY pyproject.toml README.md ./
COPY src ./src
COPY service ./service
RUN pip install --prefix=/install ".${RCSA_EXTRAS:+[$RCSA_EXTRAS]}"

FROM python:3.11-slim
ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    RCSA_STORE=/data/store \
    RCSA_WORKERS=2 \
    PROMETHEUS_MULTIPROC_DIR=/tmp/rcsa-prometheus \
    MPLCONFIGDIR=/tmp/matplotlib
COPY --from=build /install /usr/local
RUN useradd --create-home --uid 10001 --shell /usr/sbin/nologin rcsa \
    && mkdir -p /data \
    && chown rcsa:rcsa /data
USER rcsa
WORKDIR /home/rcsa
VOLUME ["/data"]
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s \
    CMD python -c "import sys, urllib.request; sys.exit(urllib.request.urlopen('http://127.0.0.1:8000/readyz', timeout=4).status != 200)"
# A fresh metrics directory per start (Prometheus multi-process mode across the workers).
CMD ["sh", "-c", "rm -rf \"$PROMETHEUS_MULTIPROC_DIR\" && mkdir -p \"$PROMETHEUS_MULTIPROC_DIR\" && exec uvicorn service.main:create_app --factory --host 0.0.0.0 --port 8000 --workers \"$RCSA_WORKERS\" --http service.http:NoDelayHTTPProtocol --proxy-headers"]
