#!/usr/bin/env bash
# Build a local stand-in for the Dockerfile's base image from Debian packages, for machines
# that cannot pull from a container registry (the image's default base is the pinned upstream
# python:3.11-slim-bookworm, see the Dockerfile's BASE_IMAGE).
#
#   sudo docker/build-base.sh                 # -> rcsa-base:bookworm-python3.11
#   docker build --build-arg BASE_IMAGE=rcsa-base:bookworm-python3.11 -t rcsa .
#
# What it makes: a minimal Debian 12 (bookworm) root file system by `debootstrap --variant=minbase`
# with Debian's python3 (3.11), python3-venv and ca-certificates, without apt lists, docs, man
# pages and locales, imported with `docker import`. Like the upstream image it has `python3`
# able to make a venv (the Dockerfile installs rcsa into /opt/venv on either base).
#
# Environment:
#   DEBIAN_MIRROR   the Debian mirror (default http://deb.debian.org/debian)
#   BASE_HOST_CA=1  (default) copy this machine's CA bundle /etc/ssl/certs/ca-certificates.crt
#                   into the image, so that pip inside `docker build` trusts what pip on this
#                   machine trusts (needed behind a TLS-intercepting proxy); 0 keeps Debian's.
# Needs root (debootstrap, chroot), debootstrap and a running Docker daemon.
set -euo pipefail

tag=${1:-rcsa-base:bookworm-python3.11}
mirror=${DEBIAN_MIRROR:-http://deb.debian.org/debian}
command -v debootstrap >/dev/null || { echo "build-base: debootstrap is missing (apt-get install debootstrap)" >&2; exit 1; }
docker info >/dev/null 2>&1 || { echo "build-base: no Docker daemon answers" >&2; exit 1; }

root=$(mktemp -d /tmp/rcsa-base.XXXXXX)
trap 'rm -rf "$root"' EXIT
echo "build-base: debootstrap bookworm into $root (a few minutes)" >&2
debootstrap --variant=minbase --include=python3,python3-venv,ca-certificates bookworm "$root" "$mirror" >&2
chroot "$root" apt-get clean
rm -rf "$root"/var/lib/apt/lists/* "$root"/var/cache/apt/* "$root"/var/log/* \
       "$root"/usr/share/doc/* "$root"/usr/share/man/* "$root"/usr/share/info/*
find "$root"/usr/share/locale -mindepth 1 -maxdepth 1 ! -name 'locale.alias' -exec rm -rf {} +
if [ "${BASE_HOST_CA:-1}" = 1 ] && [ -s /etc/ssl/certs/ca-certificates.crt ]; then
    cp /etc/ssl/certs/ca-certificates.crt "$root"/etc/ssl/certs/ca-certificates.crt
fi
version=$(chroot "$root" python3 -c 'import platform; print(platform.python_version())')
tar --numeric-owner -C "$root" -c . | docker import \
    --change 'ENV LANG=C.UTF-8' \
    --change 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
    --change 'CMD ["python3"]' \
    --message "debootstrap bookworm minbase + python3 $version (docker/build-base.sh)" - "$tag" >/dev/null
echo "build-base: $tag (Debian bookworm, Python $version): $(docker image inspect -f '{{.Size}}' "$tag" | awk '{printf "%.0f MB", $1/1e6}')" >&2
