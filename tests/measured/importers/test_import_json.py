"""The contract's measurement JSON: upload form, export → re-import round trip, refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.importers import (
    measurement_from_contract,
    measurement_to_contract,
    read_contract_json,
)
from rcsa.measured.store import MeasurementStore

from ._synth import ARTIFACT, two_mode_receptance

F = np.arange(5.0, 1005.0, 5.0)
H = two_mode_receptance(F)


def _c(z):
    return {"real": np.real(z).tolist(), "imag": np.imag(z).tolist()}


def point_doc() -> dict:
    return {
        "spindle_id": "mc1-hsk63",
        "direction": "x",
        "plane": "spindle_nose",
        "kind": "point_receptance",
        "frequency_hz": F.tolist(),
        "h": _c(H),
        "l": _c(-3 * H),
        "n": _c(-3 * H),
        "p": _c(20 * H),
    }


def test_contract_upload_and_export_round_trip_bit_exact(tmp_path):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(point_doc()))
    m = read_contract_json(path)
    assert m.frfs["h"].tobytes() == H.tobytes()
    assert m.provenance.source_format == "contract_json" and m.provenance.source_file == "m.json"
    store = MeasurementStore(tmp_path / "store")
    stored = store.get(store.put(m))
    exported = json.loads(
        json.dumps(measurement_to_contract(stored))
    )  # float64 survives JSON exactly
    assert exported["units"]["p"] == "rad/(N*m)" and exported["id"] == stored.id
    again = measurement_from_contract(exported)
    for k in "hlnp":
        assert again.frfs[k].tobytes() == stored.frfs[k].tobytes()
    assert again.meta == stored.meta
    assert again.id is None  # a re-import is a new measurement


def test_artifact_document_with_coherence_and_overrides():
    doc = {
        "direction": "y",
        "plane": "holder_tip",
        "kind": "artifact_frfs",
        "frequency_hz": F.tolist(),
        "h11": _c(H),
        "h21": _c(0.5 * H),
        "h22": _c(0.7 * H),
        "points_m": [0.0, 0.03],
        "artifact": ARTIFACT,
        "coherence": {"h21": np.full(F.size, 0.9).tolist()},
        "notes": "blank",
    }
    m = measurement_from_contract(
        doc, overrides={"spindle_id": "s7", "direction": "y", "machine": None}
    )
    assert m.meta.spindle_id == "s7" and m.meta.points_m == (0.0, 0.03)
    assert dict(m.meta.artifact) == ARTIFACT
    assert set(m.coherence) == {"h21"}
    with pytest.raises(InputError) as err:
        measurement_from_contract(doc, overrides={"spindle_id": "s7", "direction": "x"})
    assert err.value.field == "direction"


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d.pop("p"), "p"),
        (lambda d: d.pop("spindle_id"), "spindle_id"),
        (lambda d: d.update(colour="red"), "colour"),
        (lambda d: d.update(kind="modal"), "kind"),
        (lambda d: d["h"]["real"].append(1.0), "h.imag"),
        (lambda d: d["h"]["real"].__setitem__(3, None), "h.real"),
        (lambda d: d["l"].pop("imag"), "l"),
        (lambda d: d.update(frequency_hz=F[::-1].tolist()), "frequency_hz"),
        (lambda d: d["frequency_hz"].__setitem__(0, 0.0), "frequency_hz"),
        (lambda d: d["n"]["imag"].__setitem__(2, float("nan")), "n"),
        (lambda d: d.update(coherence=[0.5] * F.size), "coherence"),
    ],
)
def test_bad_documents_name_the_field(change, field):
    doc = point_doc()
    change(doc)
    with pytest.raises(InputError) as err:
        measurement_from_contract(doc)
    assert err.value.field == field, str(err.value)


def test_invalid_json_file(tmp_path):
    (tmp_path / "x.json").write_text("{not json")
    with pytest.raises(InputError) as err:
        read_contract_json(tmp_path / "x.json")
    assert err.value.field == "file"
