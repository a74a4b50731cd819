"""How rcsa is installed and shipped, checked statically (``docker/smoke.sh`` runs it for real).

* ``constraints.txt`` is the one lock: it pins every requirement of ``pyproject.toml`` (core,
  every extra, the build backend), and CI (README line 2 through ``.ci/run``), the README's
  run command and the Docker image all install with ``-c constraints.txt``.
* The image: a base pinned by digest, the dependencies installed in a layer of their own
  before the code is copied, a non-root user, a health check, no anonymous ``VOLUME``, only
  the package in the build context.
* Compose: one ``build:`` (one image for the service, the scheduler and the workers), the
  service published on loopback unless ``RCSA_PUBLISH`` says otherwise, read-only root file
  systems, and the store on an external volume that ``docker compose down -v`` cannot delete.
"""

from __future__ import annotations

import re
import tomllib

import pytest
import yaml

from tests.helpers import REPO

LOCK = "constraints.txt"


def _name(requirement: str) -> str:
    """The normalised project name of a requirement string (``dask[distributed]>=2024.8`` → ``dask``)."""
    return re.sub(r"[-_.]+", "-", re.match(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)", requirement).group(1)).lower()


def _pinned() -> dict[str, str]:
    pins = {}
    for line in (REPO / LOCK).read_text().splitlines():
        if line and not line.startswith("#"):
            name, _, version = line.partition("==")
            assert version, f"{LOCK}: not an exact pin: {line!r}"
            pins[_name(name)] = version
    return pins


def test_the_lock_pins_every_requirement_of_pyproject():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    wanted = [*project["project"]["dependencies"], *project["build-system"]["requires"]]
    for extra in project["project"]["optional-dependencies"].values():
        wanted += extra
    missing = sorted({_name(r) for r in wanted} - set(_pinned()))
    assert not missing, f"not in {LOCK}: {missing}; run scripts/update-constraints.sh"


def _readme_first_block() -> list[str]:
    text = (REPO / "README.md").read_text()
    return re.search(r"```bash\n(.*?)```", text, re.S).group(1).splitlines()


def test_ci_and_the_readme_install_with_the_lock():
    block = _readme_first_block()
    assert len(block) == 2, block  # .ci/run executes line 2
    for line in block:
        assert f"pip install -q -c {LOCK} -e " in line, line
    assert "sed -n 2p" in (REPO / ".ci" / "run").read_text()


def test_the_image_pins_its_base_caches_its_dependencies_and_runs_unprivileged():
    lines = [ln.strip() for ln in (REPO / "Dockerfile").read_text().splitlines() if ln.strip()
             and not ln.lstrip().startswith("#")]
    instructions = [ln.split()[0] for ln in lines if ln.split()[0].isupper()]
    assert "VOLUME" not in instructions  # an anonymous volume per container, and `down -v` deletes it
    base = next(ln for ln in lines if ln.startswith("ARG BASE_IMAGE="))
    assert re.fullmatch(r"ARG BASE_IMAGE=python:3\.11\.\d+-slim-bookworm@sha256:[0-9a-f]{64}", base), base
    assert {ln for ln in lines if ln.startswith("FROM ")} == {"FROM ${BASE_IMAGE}", "FROM ${BASE_IMAGE} AS requirements"}
    text = "\n".join(lines)
    final = text.index("FROM ${BASE_IMAGE}\n")  # the image's own stage
    deps, lock = text.index("COPY --from=requirements /r/requirements.txt"), text.index(f"COPY {LOCK} ")
    install, code = text.index(f"pip install -c /src/{LOCK} -r"), text.index("COPY src ")
    assert final < deps < lock < install < code  # the dependency layer is built before the code is copied
    assert "COPY pyproject.toml" not in text[final:install]  # keyed on the requirements, not the whole file
    assert "--no-deps" in text[code:]  # the code layer installs nothing else
    users = [ln.split()[1] for ln in lines if ln.startswith("USER ")]
    assert users and users[-1] not in ("root", "0")
    assert "HEALTHCHECK" in instructions


def test_the_build_context_is_only_the_package():
    patterns = [ln for ln in (REPO / ".dockerignore").read_text().splitlines() if ln and not ln.startswith("#")]
    assert patterns[0] == "*"  # an allowlist
    allowed = {p[1:].rstrip("/") for p in patterns if p.startswith("!")}
    assert {"pyproject.toml", LOCK, "src", "service"} <= allowed
    assert not allowed & {"tests", "benchmarks", ".git", ".venv", "docs", "examples"}


@pytest.fixture(scope="module")
def compose() -> dict:
    return yaml.safe_load((REPO / "docker-compose.yml").read_text())


def test_compose_builds_one_image_and_everything_runs_read_only(compose):
    services = compose["services"]
    built = [name for name, s in services.items() if "build" in s]
    assert built == ["service"]
    images = {s["image"] for s in services.values()}
    assert len(images) == 1 and images == {services["service"]["image"]}
    for name, s in services.items():
        assert s.get("read_only") is True and "/tmp" in s.get("tmpfs", []), name
        assert s.get("user") in (None, "10001", "10001:10001"), name  # the image's unprivileged user


def test_compose_publishes_on_loopback_unless_asked(compose):
    published = [p for s in compose["services"].values() for p in s.get("ports", [])]
    assert published == ["${RCSA_PUBLISH:-127.0.0.1}:${RCSA_PORT:-8000}:8000"]


def test_compose_keeps_the_store_on_an_external_volume(compose):
    assert compose["services"]["service"]["volumes"] == ["rcsa-store:/data"]
    volume = compose["volumes"]["rcsa-store"]
    assert volume["external"] is True  # `docker compose down -v` never deletes it
    assert volume["name"] == "${RCSA_STORE_VOLUME:-rcsa-store}"
    others = [name for name, s in compose["services"].items() if name != "service" and s.get("volumes")]
    assert not others  # the scheduler and the workers share nothing but the network


def test_compose_workers_keep_freed_memory_as_the_backend_says(compose):
    """The workers' nanny environment is :data:`rcsa.infra.compute_backends.DASK_WORKER_ENVIRON`
    (Dask reads the JSON of ``DASK_DISTRIBUTED__NANNY__PRE_SPAWN_ENVIRON`` as the config value)."""
    import ast

    from rcsa.infra.compute_backends import DASK_WORKER_ENVIRON

    workers = [s for name, s in compose["services"].items() if name.startswith("worker")]
    assert workers
    for worker in workers:
        value = worker["environment"]["DASK_DISTRIBUTED__NANNY__PRE_SPAWN_ENVIRON"]
        assert ast.literal_eval(value) == DASK_WORKER_ENVIRON


def test_the_license_and_the_python_version_are_stated_where_a_user_looks():
    """pyproject says MIT and Python >= 3.11; the LICENSE file, the sdist and the README say the same."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    meta = project["project"]
    assert meta["license"] == "MIT" and meta["license-files"] == ["LICENSE"]
    license_text = (REPO / "LICENSE").read_text()
    assert license_text.startswith("MIT License") and "WITHOUT WARRANTY OF ANY KIND" in license_text
    assert "LICENSE" in project["tool"]["hatch"]["build"]["targets"]["sdist"]["include"]
    assert meta["requires-python"] == ">=3.11"
    assert project["tool"]["mypy"]["python_version"] == "3.11"
    assert "Python ≥ 3.11" in (REPO / "README.md").read_text()
