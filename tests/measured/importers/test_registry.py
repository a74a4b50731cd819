"""read_any: one call reads every format of tests/data/measurements as its own importer does."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.importers import (
    read_any,
    read_contract_json,
    read_csv,
    read_cutpro,
    read_tap,
    read_uff,
)
from rcsa.measured.importers.registry import format_from_name, parse_points
from rcsa.measured.store import MeasurementMeta
from tests.helpers import REPO

HERE = REPO / "tests" / "data" / "measurements"
WHERE = {"spindle_id": "demo-hsk63", "direction": "x", "plane": "spindle_nose"}
META = MeasurementMeta("demo-hsk63", "x", "spindle_nose", "direct_frf")
ARTIFACT = {"diameter_m": 0.02, "stickout_m": 0.08, "material": "steel"}
ROLES = {"h11": (1, 1), "h21": (2, 1), "h22": (2, 2)}


def _same(a, b):
    assert a.frfs and set(a.frfs) == set(b.frfs)
    assert a.frequency_hz.tobytes() == b.frequency_hz.tobytes()
    for name in a.frfs:
        assert a.frfs[name].tobytes() == b.frfs[name].tobytes(), name
    assert a.meta == b.meta


def test_every_format_reads_as_its_own_importer_reads_it():
    _same(read_any(HERE / "direct_frf_um_per_n.csv", units="um/N", **WHERE),
          read_csv(HERE / "direct_frf_um_per_n.csv", META, units="um/N"))
    _same(read_any(HERE / "direct_frf_mag_phase_deg.tsv", units="um/N", columns="f,mag,phase", phase_unit="deg",
                   **WHERE),
          read_csv(HERE / "direct_frf_mag_phase_deg.tsv", META, units="um/N", columns="f,mag,phase",
                   phase_unit="deg"))
    _same(read_any(HERE / "direct_frf.frf", **WHERE), read_cutpro(HERE / "direct_frf.frf", META))
    _same(read_any(HERE / "point_receptance.json"), read_contract_json(HERE / "point_receptance.json"))
    _same(read_any(HERE / "artifact_frfs_accelerance.uff", spindle_id="demo-hsk63", plane="spindle_nose",
                   kind="artifact_frfs", points_m="0,0.03", artifact=ARTIFACT, roles="h11=1:1,h21=2:1,h22=2:2"),
          read_uff(HERE / "artifact_frfs_accelerance.uff",
                   MeasurementMeta("demo-hsk63", "x", "spindle_nose", "artifact_frfs", points_m=(0.0, 0.03),
                                   artifact=ARTIFACT), roles=ROLES))
    tap = read_any(HERE / "tap_synthetic.txt", format="tap", force_unit="N", response_unit="m/s^2",
                   max_frequency_hz=1200, **WHERE)
    _same(tap, read_tap(HERE / "tap_synthetic.txt", META, force_unit="N", response_unit="m/s^2",
                        max_frequency_hz=1200))


@pytest.mark.parametrize(("kwargs", "field"), [
    ({**WHERE, "unit": "um/N"}, "unit"),                            # a typo is named, never ignored
    ({**WHERE, "units": "um/N", "force_unit": "N"}, "force_unit"),  # an option of another format
    ({"direction": "x", "plane": "spindle_nose", "units": "um/N"}, "spindle_id"),  # metadata missing
])
def test_read_any_refuses_what_it_cannot_use_naming_the_field(kwargs, field):
    with pytest.raises(InputError) as e:
        read_any(HERE / "direct_frf_um_per_n.csv", **kwargs)
    assert e.value.field == field


def test_the_format_comes_from_the_suffix_or_is_stated():
    assert [format_from_name(n) for n in ("a.uff", "a.UNV", "a.tsv", "a.frf", "a.json")] == \
        ["uff", "uff", "csv", "frf", "json"]
    with pytest.raises(InputError, match="cannot tell the format"):
        format_from_name("tap.txt")
    with pytest.raises(InputError) as e:
        read_any(HERE / "tap_synthetic.txt", **WHERE)
    assert e.value.field == "format"


def test_points_are_read_from_text_or_lists_and_refused_when_not_numbers():
    assert parse_points("0, 0.025") == parse_points("[0, 0.025]") == parse_points([0, 0.025]) == (0.0, 0.025)
    for bad in ("0,x", "[0, NaN]", [True, 0.1], "1e400"):
        with pytest.raises(InputError) as e:
            parse_points(bad)
        assert e.value.field == "points_m"
    np.testing.assert_equal(parse_points(None), None)
