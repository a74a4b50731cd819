"""Names, versions and fixed conventions of the measured-FRF store.

Every HDF5 object the store writes carries two attributes, ``schema`` and
``schema_version`` (anndata's ``encoding-type``/``encoding-version`` idea): the reader
dispatches on them and refuses what it does not know instead of guessing.
"""

from __future__ import annotations

import re

from rcsa.model.wire import CONVENTION, RECEPTANCE_UNITS

__all__ = [
    "ARTIFACT_FRF_NAME",
    "COHERENCE_GROUP_SCHEMA",
    "COHERENCE_SCHEMA",
    "CONVENTION",
    "DIRECTIONS",
    "FREQUENCY_SCHEMA",
    "FRF_GROUP_SCHEMA",
    "FRF_SCHEMA",
    "FRF_UNITS",
    "KINDS",
    "MEASUREMENT_SCHEMA",
    "PLANES",
    "SCHEMA_VERSION",
    "STORE_SCHEMA",
    "SUPPORTED_VERSIONS",
    "frf_unit",
]

#: Schema of the store directory marker (``rcsa-store.json``).
STORE_SCHEMA = "rcsa.store"
#: Schema of the root group of one measurement file.
MEASUREMENT_SCHEMA = "rcsa.measurement"
#: Schemas of the datasets inside a measurement file.
FREQUENCY_SCHEMA = "rcsa.frequency_hz"
FRF_SCHEMA = "rcsa.frf"
COHERENCE_SCHEMA = "rcsa.coherence"
#: Group holding the FRFs and the group holding coherences.
FRF_GROUP_SCHEMA = "rcsa.frf_group"
COHERENCE_GROUP_SCHEMA = "rcsa.coherence_group"

#: Version written by this code, and the versions it can read.
SCHEMA_VERSION = 1
SUPPORTED_VERSIONS = frozenset({1})

DIRECTIONS = ("x", "y")
PLANES = ("spindle_nose", "holder_tip")
KINDS = ("point_receptance", "artifact_frfs", "direct_frf")

#: Receptance names of an artifact test: ``h<response point><excitation point>``, points 1..9
#: counted from the artifact tip toward the spindle (``points_m`` gives their positions).
ARTIFACT_FRF_NAME = re.compile(r"^h[1-9][1-9]$")

#: Units of each stored receptance (docs/contract.md "Units"): those of the wire form.
FRF_UNITS = RECEPTANCE_UNITS

# CONVENTION (the conventions every stored receptance is expressed in, docs/physics.md §2.1) is the
# wire form's, rcsa.model.wire.CONVENTION; it is written into every measurement file.


def frf_unit(name: str) -> str:
    """Unit string of the stored receptance ``name`` (``h``, ``l``, ``n``, ``p`` or ``hij``)."""
    if name in FRF_UNITS:
        return FRF_UNITS[name]
    if ARTIFACT_FRF_NAME.match(name):
        return "m/N"
    raise KeyError(name)
