"""Print the requirements of ``pyproject.toml`` (core, plus the extras named in argv), one a line.

The Docker image installs these with ``-c constraints.txt`` in a layer of their own before the
code is copied, so that a change of the code does not reinstall the dependencies::

    python3 docker/requirements.py pyproject.toml dask > requirements.txt
"""

from __future__ import annotations

import sys
import tomllib


def main(argv: list[str]) -> None:
    with open(argv[1], "rb") as f:
        project = tomllib.load(f)["project"]
    lines = list(project["dependencies"])
    for extra in filter(None, ",".join(argv[2:]).split(",")):
        lines += project["optional-dependencies"][extra.strip()]
    sys.stdout.write("".join(f"{line}\n" for line in lines))


if __name__ == "__main__":
    main(sys.argv)
