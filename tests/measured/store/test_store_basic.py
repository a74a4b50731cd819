"""MeasurementStore: round trip, immutability, list/delete, schema tags, foreign files."""

from __future__ import annotations

import dataclasses
import json
import os

import h5py
import numpy as np
import pytest

from rcsa.errors import InputError, NotFoundError, StoreError
from rcsa.measured.store import (
    Measurement,
    MeasurementMeta,
    MeasurementStore,
    default_store_path,
    is_measurement_id,
)
from rcsa.measured.store import paths as store_paths
from rcsa.measured.store.catalogue import Catalogue
from rcsa.measured.store.hdf5io import read_measurement_file

from ._factory import ARTIFACT, assert_same_data, make_measurement

KINDS = ["direct_frf", "point_receptance", "artifact_frfs"]


@pytest.fixture
def store(tmp_path):
    return MeasurementStore(tmp_path / "store")


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("seed", [1, 2])
def test_put_get_round_trip_is_bit_exact(store, kind, seed):
    m = make_measurement(seed, kind)
    mid = store.put(m)
    assert is_measurement_id(mid)
    got = store.get(mid)
    assert_same_data(got, m)
    assert got.id == mid
    assert got.created_utc.endswith("Z") and got.created_utc[:4].isdigit()
    assert got.software_version
    assert m.id is None  # the input object is untouched


def test_point_receptance_gives_a_receptance(store):
    got = store.get(store.put(make_measurement(3, "point_receptance", nfreq=50)))
    r = got.receptance()
    assert r.values.shape == (50, 2, 2)
    assert r.h.tobytes() == got.frfs["h"].tobytes()
    assert r.p.tobytes() == got.frfs["p"].tobytes()


def test_returned_measurement_is_immutable(store):
    got = store.get(store.put(make_measurement(5)))
    with pytest.raises(ValueError, match="read-only"):
        got.frfs["h"][0] = 0
    with pytest.raises(ValueError, match="read-only"):
        got.frequency_hz[0] = 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        got.id = "m-000000000000"  # type: ignore[misc]
    with pytest.raises(TypeError):
        got.frfs["x"] = got.frfs["h"]  # type: ignore[index]
    with pytest.raises(TypeError):
        got.meta.artifact["a"] = 1 if got.meta.artifact else None  # type: ignore[index]


def test_measurement_copies_its_inputs():
    f = np.array([1.0, 2.0, 3.0])
    h = np.array([1e-6, 2e-6, 3e-6], dtype=complex)
    m = Measurement(f, {"h": h}, MeasurementMeta("s", "x", "spindle_nose", "direct_frf"))
    h[0] = 99
    f[0] = 0.5
    assert m.frfs["h"][0] == 1e-6 and m.frequency_hz[0] == 1.0


def test_list_filters_and_delete(store):
    ids = [store.put(make_measurement(s)) for s in range(6)]
    assert [i.id for i in store.list()] == ids  # oldest first
    sp0 = store.list("spindle-0")
    assert {i.id for i in sp0} == {ids[0], ids[3]}
    assert all(i.meta.spindle_id == "spindle-0" for i in sp0)
    assert {i.id for i in store.list(direction="y")} == {ids[1], ids[3], ids[5]}
    assert store.list(kind="artifact_frfs") == []
    info = store.list()[0]
    assert info.n_frequencies == make_measurement(0).n_frequencies
    assert info.frf_names == ("h",)
    store.delete(ids[0])
    assert ids[0] not in store
    assert [i.id for i in store.list()] == ids[1:]
    with pytest.raises(NotFoundError):
        store.get(ids[0])
    with pytest.raises(NotFoundError):
        store.delete(ids[0])
    assert (store.path / "deleted" / ids[0]).exists()


def test_deleted_ids_are_never_reused(store, monkeypatch):
    mid = store.put(make_measurement(1))
    store.delete(mid)
    fresh = "m-00000000abcd"
    draws = iter([mid, fresh])
    monkeypatch.setattr(store_paths, "new_measurement_id", lambda: next(draws))
    assert store.put(make_measurement(2)) == fresh


@pytest.mark.parametrize(
    "bad", ["../etc/passwd", "m-123", "M-0123456789AB", "", "m-0123456789ab/../x"]
)
def test_bad_ids_are_not_found_never_opened(store, bad):
    with pytest.raises(NotFoundError):
        store.get(bad)
    with pytest.raises(NotFoundError):
        store.delete(bad)


def test_every_object_carries_schema_and_version(store):
    mid = store.put(make_measurement(1, "artifact_frfs"))
    seen = []
    with h5py.File(store.path / "measurements" / f"{mid}.h5", "r") as f:
        assert f.attrs["schema"] == "rcsa.measurement" and f.attrs["schema_version"] == 1

        def visit(name, obj):
            seen.append(name)
            assert str(obj.attrs["schema"]).startswith("rcsa."), name
            assert obj.attrs["schema_version"] == 1, name

        f.visititems(visit)
        assert f["frf/h21"].attrs["units"] == "m/N"
        assert f["frf/frequency_hz"].attrs["units"] == "Hz"
        assert f["frf"].attrs["NX_class"] == "NXdata"
        assert json.loads(f.attrs["artifact_json"]) == ARTIFACT
    assert {"frf", "frf/frequency_hz", "frf/h11", "coherence", "coherence/h11"} <= set(seen)
    marker = json.loads((store.path / "rcsa-store.json").read_text())
    assert marker["schema"] == "rcsa.store" and marker["schema_version"] == 1


def _plant(store, name, build):
    path = store.path / "measurements" / f"{name}.h5"
    with h5py.File(path, "w") as f:
        build(f)
    return name


def test_foreign_and_newer_files_are_refused_with_a_clear_message(store):
    good = store.put(make_measurement(1))
    foreign = _plant(
        store,
        "m-0000000000f1",
        lambda f: f.attrs.update({"schema": "anndata", "schema_version": 1}),
    )
    untagged = _plant(store, "m-0000000000f2", lambda f: f.create_group("x"))
    newer = _plant(
        store,
        "m-0000000000f3",
        lambda f: f.attrs.update({"schema": "rcsa.measurement", "schema_version": 99}),
    )
    garbage = "m-0000000000f4"
    (store.path / "measurements" / f"{garbage}.h5").write_bytes(b"not hdf5 at all")
    with pytest.raises(StoreError, match="foreign schema 'anndata'"):
        store.get(foreign)
    with pytest.raises(StoreError, match="no schema"):
        store.get(untagged)
    with pytest.raises(StoreError, match="version 99 is not supported"):
        store.get(newer)
    with pytest.raises(StoreError, match="not a readable HDF5 file"):
        store.get(garbage)
    assert [i.id for i in store.list()] == [good]  # unreadable files are left out of the listing
    problems = store.check()
    assert len(problems) == 4 and all("m-0000000000f" in p for p in problems)


def test_a_nested_dataset_with_a_foreign_tag_is_refused(store):
    mid = store.put(make_measurement(2))
    src = store.path / "measurements" / f"{mid}.h5"
    dst = store.path / "measurements" / "m-00000000abcd.h5"
    dst.write_bytes(src.read_bytes())
    with h5py.File(dst, "a") as f:
        f["frf/h"].attrs["schema"] = "other.thing"
    with pytest.raises(StoreError, match="/frf/h: foreign schema"):
        read_measurement_file(dst)


def test_store_refuses_a_foreign_directory(tmp_path):
    d = tmp_path / "home"
    d.mkdir()
    (d / "thesis.tex").write_text("x")
    with pytest.raises(StoreError, match="not an rcsa store"):
        MeasurementStore(d)
    e = tmp_path / "other"
    e.mkdir()
    (e / "rcsa-store.json").write_text(json.dumps({"schema": "zarr", "schema_version": 1}))
    with pytest.raises(StoreError, match="foreign store schema"):
        MeasurementStore(e)
    (e / "rcsa-store.json").write_text(json.dumps({"schema": "rcsa.store", "schema_version": 7}))
    with pytest.raises(StoreError, match="version 7"):
        MeasurementStore(e)


def test_default_location(monkeypatch, tmp_path):
    monkeypatch.setenv("RCSA_STORE", str(tmp_path / "env-store"))
    assert default_store_path() == tmp_path / "env-store"
    store = MeasurementStore()
    assert store.path == tmp_path / "env-store" and (store.path / "rcsa-store.json").is_file()
    monkeypatch.delenv("RCSA_STORE")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert default_store_path() == tmp_path / "xdg" / "rcsa" / "store"
    monkeypatch.delenv("XDG_DATA_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_store_path() == tmp_path / "home" / ".local" / "share" / "rcsa" / "store"


def test_catalogue_is_a_rebuildable_cache(store):
    ids = [store.put(make_measurement(s)) for s in range(3)]
    # a file without its catalogue row (writer killed between rename and insert)
    Catalogue(store.path / "index.sqlite").remove([ids[1]])
    assert [i.id for i in store.list()] == ids
    # a row without its file
    (store.path / "measurements" / f"{ids[2]}.h5").rename(store.path / "tmp" / "x")
    assert [i.id for i in store.list()] == ids[:2]
    (store.path / "tmp" / "x").rename(store.path / "measurements" / f"{ids[2]}.h5")
    # a copy under another name carries the wrong id inside: not listed, reported
    src = store.path / "measurements" / f"{ids[0]}.h5"
    (store.path / "measurements" / "m-00000000beef.h5").write_bytes(src.read_bytes())
    assert [i.id for i in store.list()] == ids
    assert store.check() == [f"m-00000000beef: file carries id {ids[0]!r}"]
    (store.path / "measurements" / "m-00000000beef.h5").unlink()
    # lost index
    for p in store.path.glob("index.sqlite*"):
        p.unlink()
    assert [i.id for i in store.list()] == ids
    # corrupt index: listing falls back to the files, rebuild repairs it
    (store.path / "index.sqlite").write_bytes(b"garbage" * 100)
    assert [i.id for i in store.list()] == ids
    assert store.rebuild_index() == 3
    assert [i.id for i in store.list(spindle_id="spindle-1")] == [ids[1]]


def test_stale_temporary_files_are_cleaned_by_the_next_writer(store):
    stale = store.path / "tmp" / "m-0123456789ab.h5.tmp"
    stale.write_bytes(b"half a file")
    assert [i.id for i in store.list()] == []  # readers never look into tmp/
    store.put(make_measurement(1))
    assert os.listdir(store.path / "tmp") == []


def test_solid_artifact_with_zero_bore_is_accepted():
    art = {**ARTIFACT, "inner_diameter_m": 0.0}
    meta = MeasurementMeta(
        "s", "x", "spindle_nose", "artifact_frfs", points_m=(0, 0.02), artifact=art
    )
    assert meta.artifact["inner_diameter_m"] == 0.0


def test_invalid_measurements_name_the_field():
    meta = MeasurementMeta("s", "x", "spindle_nose", "direct_frf")
    f = np.array([1.0, 2.0])
    cases = [
        (lambda: MeasurementMeta("s", "z", "spindle_nose", "direct_frf"), "direction"),
        (lambda: MeasurementMeta("", "x", "spindle_nose", "direct_frf"), "spindle_id"),
        (lambda: MeasurementMeta("s", "x", "tool_tip", "direct_frf"), "plane"),
        (
            lambda: MeasurementMeta("s", "x", "spindle_nose", "artifact_frfs", points_m=(0, 0.02)),
            "artifact",
        ),
        (
            lambda: MeasurementMeta("s", "x", "spindle_nose", "artifact_frfs", artifact=ARTIFACT),
            "points_m",
        ),
        (
            lambda: MeasurementMeta(
                "s", "x", "spindle_nose", "artifact_frfs", points_m=(0.02, 0.01), artifact=ARTIFACT
            ),
            "points_m",
        ),
        (
            lambda: MeasurementMeta(
                "s",
                "x",
                "spindle_nose",
                "artifact_frfs",
                points_m=(0, 0.02),
                artifact={**ARTIFACT, "inner_diameter_m": 0.02},
            ),
            "artifact.inner_diameter_m",
        ),
        (
            lambda: MeasurementMeta(
                "s",
                "x",
                "spindle_nose",
                "artifact_frfs",
                points_m=(0, 0.02),
                artifact={**ARTIFACT, "diameter_m": -1},
            ),
            "artifact.diameter_m",
        ),
        (lambda: Measurement(f, {"h": [1, 2], "l": [1, 2]}, meta), "frfs"),
        (lambda: Measurement(f, {"h": [1, np.nan]}, meta), "h"),
        (lambda: Measurement(f, {"h": [1, 2, 3]}, meta), "h"),
        (lambda: Measurement([2.0, 1.0], {"h": [1, 2]}, meta), "frequency_hz"),
        (lambda: Measurement([0.0, 1.0], {"h": [1, 2]}, meta), "frequency_hz"),
        (lambda: Measurement(f, {"h": [1, 2]}, meta, coherence={"h": [0.5, 1.5]}), "coherence.h"),
    ]
    for build, field in cases:
        with pytest.raises(InputError) as err:
            build()
        assert err.value.field == field, (field, str(err.value))


def test_threads_share_one_store(store):
    import threading

    ids, errors = [], []

    def writer(k):
        try:
            ids.extend(store.put(make_measurement(100 * k + j, nfreq=30)) for j in range(8))
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=writer, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == [] and len(set(ids)) == 32
    assert {i.id for i in store.list()} == set(ids)
