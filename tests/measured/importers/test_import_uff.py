"""UFF 58 import: quantities from data-type codes, units from dataset 164 / labels /
declaration, roles, refusals; the same receptance through UFF (ASCII, binary) and CSV.

Tolerances (relative, per value):
* binary UFF, receptance in SI: bit-exact (doubles written and read, factor 1.0);
* binary UFF with a conversion (accelerance, inch units, g): 1e-14 — the test's forward
  conversion and the importer's inverse each round at most twice (≤ 4 ulp ≈ 9e-16);
* ASCII UFF: 1e-11 — pyuff writes 12 significant digits (``%20.11e``), a 5e-12 rounding;
* CSV in µm/N written with ``repr`` (17 digits, exact): 1e-14 — one scaling each way.
"""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.measured.importers import read_csv, read_uff
from rcsa.measured.importers.units import STANDARD_GRAVITY_M_S2
from rcsa.measured.store import MeasurementStore

from ._synth import ARTIFACT_META, IN_FORCE, IN_LENGTH, META, frf58, two_mode_receptance, write_uff

F = np.arange(10.0, 3010.0, 3.0)  # integers: exact in pyuff's %13.5e abscissa too
H = two_mode_receptance(F)
W2 = (2 * np.pi * F) ** 2
SI = (1, 1.0, 1.0)


@pytest.mark.parametrize("binary", [0, 1])
@pytest.mark.parametrize("spacing", [0, 1])
@pytest.mark.parametrize("quantity", ["receptance", "accelerance", "mobility"])
def test_uff_with_dataset_164_imports_receptance(tmp_path, binary, spacing, quantity):
    data, code = {
        "receptance": (H, 8),
        "accelerance": (-W2 * H, 12),
        "mobility": (1j * np.sqrt(W2) * H, 11),
    }[quantity]
    path = write_uff(
        tmp_path / "a.uff", [frf58(F, data, binary=binary, numerator=code, spacing=spacing)], SI
    )
    m = read_uff(path, META)
    assert m.provenance.source_format == ("uff58b" if binary else "uff58")
    assert m.provenance.original_quantity == quantity
    np.testing.assert_array_equal(m.frequency_hz, F)
    if binary and quantity == "receptance":
        assert m.frfs["h"].tobytes() == H.tobytes()
    else:
        np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-14 if binary else 1e-11, atol=0)


def test_same_receptance_through_uff_ascii_binary_and_csv_um_per_n(tmp_path):
    store = MeasurementStore(tmp_path / "store")
    ids = {
        "uff-bin-recept": store.put(
            read_uff(write_uff(tmp_path / "1.uff", [frf58(F, H, binary=1)], SI), META)
        ),
        "uff-bin-accel": store.put(
            read_uff(
                write_uff(tmp_path / "2.uff", [frf58(F, -W2 * H, binary=1, numerator=12)], SI), META
            )
        ),
        "uff-asc-recept": store.put(
            read_uff(write_uff(tmp_path / "3.uff", [frf58(F, H)], SI), META)
        ),
        "uff-asc-accel": store.put(
            read_uff(write_uff(tmp_path / "4.uff", [frf58(F, -W2 * H, numerator=12)], SI), META)
        ),
    }
    um = H * 1e6
    csv = "# tool tip, um/N\nfrequency_hz,re_um_n,im_um_n\n" + "".join(
        f"{f:.17g},{z.real:.17g},{z.imag:.17g}\n" for f, z in zip(F, um, strict=True)
    )
    (tmp_path / "5.csv").write_text(csv)
    ids["csv-um"] = store.put(read_csv(tmp_path / "5.csv", META, units="µm/N"))
    tol = {
        "uff-bin-recept": 0.0,
        "uff-bin-accel": 1e-14,
        "uff-asc-recept": 1e-11,
        "uff-asc-accel": 1e-11,
        "csv-um": 1e-14,
    }
    for name, mid in ids.items():
        got = store.get(mid)
        assert got.frequency_hz.tobytes() == F.tobytes(), name
        np.testing.assert_allclose(got.frfs["h"], H, rtol=tol[name], atol=0, err_msg=name)
    assert store.get(ids["uff-bin-recept"]).frfs["h"].tobytes() == H.tobytes()
    assert store.get(ids["csv-um"]).provenance.original_units == "µm/N"


def test_inch_units_from_dataset_164(tmp_path):
    h_in = H * IN_LENGTH / IN_FORCE  # in/lbf
    m = read_uff(
        write_uff(tmp_path / "in.uff", [frf58(F, h_in, binary=1)], (7, IN_LENGTH, IN_FORCE)), META
    )
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-14, atol=0)
    assert "code 7" in m.provenance.original_units


def test_g_based_accelerance_declared_by_the_caller(tmp_path):
    a_g = -W2 * H / STANDARD_GRAVITY_M_S2
    path = write_uff(tmp_path / "g.uff", [frf58(F, a_g, binary=1, numerator=12)])
    with pytest.raises(InputError) as err:
        read_uff(path, META)
    assert err.value.field == "units" and "declare" in err.value.rule
    m = read_uff(path, META, units="g/N")
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-14, atol=0)
    assert m.provenance.original_units == "g/N (declared)"


def test_units_from_axis_labels_and_conflicts(tmp_path):
    good = write_uff(
        tmp_path / "l.uff",
        [frf58(F, -W2 * H, binary=1, numerator=12, num_label="m/s^2", den_label="N")],
    )
    np.testing.assert_allclose(read_uff(good, META).frfs["h"], H, rtol=1e-14, atol=0)
    g_labels = [frf58(F, -W2 * H, binary=1, numerator=12, num_label="g", den_label="N")]
    clash = write_uff(tmp_path / "c.uff", g_labels, SI)
    with pytest.raises(InputError, match="disagree") as err:
        read_uff(clash, META)
    assert err.value.field == "units"
    with pytest.raises(InputError, match="data-type codes say accelerance") as err:
        read_uff(good, META, units="m/N")
    assert err.value.field == "units"


def test_unknown_codes_need_a_declared_quantity(tmp_path):
    path = write_uff(tmp_path / "u.uff", [frf58(F, H, binary=1, numerator=0, denominator=0)], SI)
    with pytest.raises(InputError, match="do not say whether") as err:
        read_uff(path, META)
    assert err.value.field == "units"
    np.testing.assert_array_equal(read_uff(path, META, units="m/N").frfs["h"], H)


def test_other_function_types_are_refused(tmp_path):
    path = write_uff(tmp_path / "auto.uff", [frf58(F, np.abs(H) ** 2, func_type=2)], SI)
    with pytest.raises(InputError, match=r"function type 2 \(auto spectrum\)") as err:
        read_uff(path, META)
    assert err.value.field == "func_type"


def test_artifact_frfs_by_roles_with_coherence_and_sign(tmp_path):
    h11, h21, h22 = H, 0.7 * H, 0.9 * H
    coh = np.linspace(0.5, 1.0, F.size)
    sets = [
        frf58(F, h11, binary=1, rsp=(1, 2), ref=(1, 2)),
        frf58(F, -h21, binary=1, rsp=(2, -2), ref=(1, 2)),  # response measured along -Y
        frf58(F, h22, binary=1, rsp=(2, 2), ref=(2, 2)),
        frf58(F, coh, binary=1, func_type=6, rsp=(1, 2), ref=(1, 2), numerator=0, denominator=0),
    ]
    path = write_uff(tmp_path / "art.uff", sets, SI)
    with pytest.raises(InputError) as err:
        read_uff(path, ARTIFACT_META)
    assert err.value.field == "roles"
    with pytest.raises(InputError) as err:
        read_uff(path, ARTIFACT_META, roles={"h11": (1, 1), "h21": (2, 1), "h22": (3, 3)})
    assert err.value.field == "roles.h22"
    m = read_uff(path, ARTIFACT_META, roles={"h11": (1, 1), "h21": (2, 1), "h22": (2, 2)})
    assert m.frfs["h11"].tobytes() == h11.tobytes()
    assert m.frfs["h21"].tobytes() == h21.tobytes()
    assert m.frfs["h22"].tobytes() == h22.tobytes()
    assert m.coherence["h11"].tobytes() == coh.tobytes()
    assert any("sign flipped" in c for c in m.provenance.conversions)


def test_zero_hz_row_is_refused_unless_dropped_and_bytes_are_accepted(tmp_path):
    f0 = np.concatenate([[0.0], F])
    h0 = np.concatenate([[1e-9 + 0j], H])
    path = write_uff(tmp_path / "z.uff", [frf58(f0, h0, binary=1)], SI)
    with pytest.raises(InputError, match="0 Hz") as err:
        read_uff(path, META)
    assert err.value.field == "frequency_hz"
    m = read_uff(path.read_bytes(), META, drop_nonpositive=True, file_name="upload.uff")
    assert m.frfs["h"].tobytes() == H.tobytes()
    assert m.provenance.source_file == "upload.uff"
    assert "dropped 1 row(s) at f <= 0 Hz" in m.provenance.conversions


def test_a_file_that_is_not_uff_is_refused(tmp_path):
    path = tmp_path / "junk.uff"
    path.write_text("    -1\n    58\nthis is not a dataset\n")
    with pytest.raises(InputError) as err:
        read_uff(path, META)
    assert err.value.field == "file"
    with pytest.raises(InputError, match="no such file"):
        read_uff(tmp_path / "missing.uff", META)
