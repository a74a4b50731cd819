"""UFF files as pyuff's own writer makes them: several unit systems, response directions ±X/±Y,
scalar FRFs, non-FRF datasets next to the FRFs, truncated copies. Each is read right or
refused with the reason; pyuff never writes to standard output.

Tolerances: binary 58b (doubles) through one unit factor, 1e-14 (a few roundings); ASCII
58 is written with 12 significant digits (%20.11e), 1e-11.
"""

from __future__ import annotations

import numpy as np
import pytest
import pyuff

from rcsa.errors import InputError
from rcsa.measured.importers import read_uff
from rcsa.measured.importers.uff58 import _quiet_pyuff

from ._synth import META, frf58, two_mode_receptance, write_uff

F = np.arange(10.0, 3010.0, 3.0)
H = two_mode_receptance(F)
W2 = (2 * np.pi * F) ** 2
SI = (1, 1.0, 1.0)
LBF_N = 0.45359237 * 9.80665
DIRECT = {"spindle_id": "mc1", "plane": "spindle_nose"}  # no direction: the file's is used

#: Unit systems of dataset 164 (I-DEAS codes), as (code, length unit in m, force unit in N);
#: the dataset stores "file units per SI unit", i.e. 1/length and 1/force.
UNIT_SYSTEMS = {
    "SI m/N": (1, 1.0, 1.0),
    "BG ft/lbf": (2, 0.3048, LBF_N),
    "MG m/kgf": (3, 1.0, 9.80665),
    "MM mm/mN": (5, 1e-3, 1e-3),
    "IN in/lbf": (7, 0.0254, LBF_N),
}


@pytest.mark.parametrize("binary", [0, 1], ids=["ascii", "binary"])
@pytest.mark.parametrize("system", list(UNIT_SYSTEMS))
@pytest.mark.parametrize("quantity", ["receptance", "accelerance"])
def test_unit_systems_of_dataset_164(tmp_path, binary, system, quantity):
    code, length_m, force_n = UNIT_SYSTEMS[system]
    si, numerator = (H, 8) if quantity == "receptance" else (-W2 * H, 12)
    in_file = si * force_n / length_m  # length/force (time is always s)
    path = write_uff(
        tmp_path / "u.uff", [frf58(F, in_file, binary=binary, numerator=numerator)],
        (code, 1 / length_m, 1 / force_n),
    )  # fmt: skip
    m = read_uff(path, META)
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-14 if binary else 1e-11, atol=0)
    assert f"code {code}" in m.provenance.original_units


@pytest.mark.parametrize(
    ("rsp_dir", "ref_dir", "sign"), [(2, 2, 1), (-2, 2, -1), (2, -2, -1), (-2, -2, 1)]
)
def test_response_direction_y_is_the_measurements_direction(tmp_path, rsp_dir, ref_dir, sign):
    path = write_uff(
        tmp_path / "y.uff", [frf58(F, sign * H, binary=1, rsp=(1, rsp_dir), ref=(1, ref_dir))], SI
    )
    m = read_uff(path, DIRECT)  # direction left out: from the file
    assert m.meta.direction == "y" and m.frfs["h"].tobytes() == H.tobytes()
    assert "direction y from the file (FRFs along Y)" in m.provenance.conversions
    assert read_uff(path, {**DIRECT, "direction": "y"}).frfs["h"].tobytes() == H.tobytes()
    with pytest.raises(InputError) as err:
        read_uff(path, META)  # META says x
    e = err.value
    assert (
        e.field == "direction"
        and "along Y (direction code 2)" in e.rule
        and "'x' was given" in e.rule
    )


def test_x_and_y_in_one_file_need_a_direction(tmp_path):
    sets = [
        frf58(F, H, binary=1, rsp=(1, 1), ref=(1, 1)),
        frf58(F, 0.5 * H, binary=1, rsp=(1, 2), ref=(1, 2)),
    ]
    path = write_uff(tmp_path / "xy.uff", sets, SI)
    with pytest.raises(InputError, match="holds FRFs along X and Y; say which") as err:
        read_uff(path, DIRECT)
    assert err.value.field == "direction"
    assert read_uff(path, {**DIRECT, "direction": "x"}).frfs["h"].tobytes() == H.tobytes()
    y = read_uff(path, {**DIRECT, "direction": "y"})
    assert y.frfs["h"].tobytes() == (0.5 * H).tobytes()
    assert any("along X, not y" in c for c in y.provenance.conversions)


def test_z_and_mixed_axes_are_refused(tmp_path):
    z = write_uff(tmp_path / "z.uff", [frf58(F, H, binary=1, rsp=(1, 3), ref=(1, 3))], SI)
    with pytest.raises(InputError, match="along Z .* lateral, x or y") as err:
        read_uff(z, DIRECT)
    assert err.value.field == "direction"
    mixed = write_uff(tmp_path / "m.uff", [frf58(F, H, binary=1, rsp=(1, 1), ref=(1, 2))], SI)
    with pytest.raises(InputError, match="response along X but reference along Y") as err:
        read_uff(mixed, META)
    assert err.value.field == "rsp_dir"


def test_scalar_frfs_need_an_explicit_direction(tmp_path):
    path = write_uff(tmp_path / "s.uff", [frf58(F, H, binary=0, rsp=(1, 0), ref=(1, 0))], SI)
    for meta in (DIRECT, META):
        with pytest.raises(InputError, match="scalar .*scalar_direction=") as err:
            read_uff(path, meta)
        assert err.value.field == "scalar_direction"
    m = read_uff(path, DIRECT, scalar_direction="x")
    assert m.meta.direction == "x"
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-11, atol=0)
    assert (
        "scalar FRFs (direction code 0) taken as x (scalar_direction)" in m.provenance.conversions
    )
    assert read_uff(path, {**DIRECT, "direction": "y"}, scalar_direction="y").meta.direction == "y"
    with pytest.raises(InputError, match="'x' but direction 'y' was given") as err:
        read_uff(path, {**DIRECT, "direction": "y"}, scalar_direction="x")
    assert err.value.field == "scalar_direction"
    with pytest.raises(InputError, match="must be x or y"):
        read_uff(path, DIRECT, scalar_direction="z")
    directional = write_uff(tmp_path / "d.uff", [frf58(F, H, binary=1)], SI)
    with pytest.raises(InputError, match="carry directions") as err:
        read_uff(directional, DIRECT, scalar_direction="x")
    assert err.value.field == "scalar_direction"


#: A permanent-groups dataset as test-lab exports carry it; pyuff prints its content on reading.
G2467 = (
    "    -1\n  2467\n" + "".join(f"{v:10d}" for v in (1, 0, 0, 0, 0, 0, 0, 2)) + "\n"
    + f"{'tool tip':<40}\n" + "".join(f"{v:10d}" for v in (8, 1, 0, 0, 8, 2, 0, 0)) + "\n    -1\n"
)  # fmt: skip


def _mixed_file(tmp_path, binary=0):
    t = np.arange(0.0, 0.1, 1e-4)
    nodes = pyuff.prepare_15(node_nums=[1, 2], def_cs=[0, 0], disp_cs=[0, 0], color=[1, 1],
                             x=[0.0, 0.0], y=[0.0, 0.0], z=[0.0, 0.03])  # fmt: skip
    time = pyuff.prepare_58(binary=0, func_type=1, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1,
                            data=np.sin(t), x=t, id1="hammer", rsp_ent_name="s", ref_ent_name="s",
                            abscissa_spacing=1, abscissa_spec_data_type=17,
                            ordinate_spec_data_type=13, orddenom_spec_data_type=0)  # fmt: skip
    coh = np.linspace(0.6, 1.0, F.size)
    sets = [
        nodes,
        time,
        frf58(F, np.abs(H) ** 2, binary=binary, func_type=2),  # an auto spectrum
        frf58(F, -W2 * H, binary=binary, numerator=12),
        frf58(F, coh, binary=binary, func_type=6, numerator=0, denominator=0),
        frf58(F, H, binary=binary, rsp=(1, 5), ref=(1, 5)),  # a rotational FRF
    ]
    path = write_uff(tmp_path / "mixed.uff", sets, SI)
    with path.open("a") as fh:
        fh.write(G2467)
    return path, coh


@pytest.mark.parametrize("binary", [0, 1], ids=["ascii", "binary"])
def test_non_frf_datasets_are_skipped_not_fatal(tmp_path, binary, capsys):
    path, coh = _mixed_file(tmp_path, binary)
    m = read_uff(path, DIRECT)
    np.testing.assert_allclose(m.frfs["h"], H, rtol=1e-14 if binary else 1e-11, atol=0)
    np.testing.assert_allclose(m.coherence["h"], coh, rtol=1e-14 if binary else 1e-11, atol=0)
    conv = "\n".join(m.provenance.conversions)
    assert "skipped datasets of type 15, 2467" in conv
    assert "function type 1 (time response)" in conv and "function type 2 (auto spectrum)" in conv
    assert "rotational DOF" in conv
    assert capsys.readouterr().out == ""  # nothing of pyuff on stdout
    same = read_uff(path, DIRECT, roles={"h": (1, 1)})  # --roles keeps working
    assert same.frfs["h"].tobytes() == m.frfs["h"].tobytes()


def test_a_file_of_time_signals_only_is_refused_with_what_it_holds(tmp_path):
    path = write_uff(
        tmp_path / "t.uff", [frf58(F, np.abs(H), func_type=1), frf58(F, np.abs(H), func_type=2)], SI
    )
    with pytest.raises(
        InputError, match=r"holds no FRF .*function type 1 \(time response\)"
    ) as err:
        read_uff(path, META)
    assert err.value.field == "func_type"


def test_pyuff_output_is_captured_logged_and_recorded(caplog, capsys):
    notes: list[str] = []
    with _quiet_pyuff(notes):
        print("Dataset location 5 has not been implemented yet")  # noqa: T201 - pyuff's style
    assert capsys.readouterr().out == ""
    assert notes == ["pyuff: printed: Dataset location 5 has not been implemented yet"]
    assert "pyuff: printed" in caplog.text


@pytest.mark.parametrize("binary", [0, 1], ids=["ascii", "binary"])
@pytest.mark.parametrize("cut", [7, 200, 5000])
def test_truncated_copies_are_refused(tmp_path, binary, cut):
    sets = [frf58(F, H, binary=binary), frf58(F, 0.5 * H, binary=binary, rsp=(2, 1))]
    data = write_uff(tmp_path / "w.uff", sets, SI).read_bytes()
    roles = {"h": (2, 1)}
    np.testing.assert_allclose(
        read_uff(data, DIRECT, roles=roles).frfs["h"], 0.5 * H, rtol=1e-11, atol=0
    )
    # only the final newline lost: the file is whole
    assert read_uff(data[:-1], DIRECT, roles=roles).n_frequencies == F.size
    with pytest.raises(InputError, match="truncated") as err:
        read_uff(data[:-cut], DIRECT, roles=roles, file_name="w.uff")
    assert err.value.field == "file"


def test_missing_values_inside_a_closed_dataset_are_refused(tmp_path):
    path = write_uff(tmp_path / "a.uff", [frf58(F, H)], SI)
    lines = path.read_text().splitlines(keepends=True)
    first = next(i for i, ln in enumerate(lines) if ln.startswith("  1.00000e+01"))
    del lines[first + 100 : first + 110]  # ten data lines lost, the closing -1 kept
    path.write_text("".join(lines))
    with pytest.raises(InputError, match="holds 990 values but its header says 1000") as err:
        read_uff(path, META)
    assert err.value.field == "file"


def test_cli_prints_valid_json_for_a_file_pyuff_talks_about(tmp_path):
    import json

    from typer.testing import CliRunner

    from rcsa.cli.store_cmd import store_app

    path, _ = _mixed_file(tmp_path)
    args = [
        "import",
        str(path),
        "--store",
        str(tmp_path / "s"),
        "--spindle-id",
        "mc1",
        "--plane",
        "spindle_nose",
    ]
    result = CliRunner().invoke(store_app, args)  # the runner's stdout is what pyuff would print to
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)  # nothing but JSON on stdout
    assert out["direction"] == "x" and out["source"]["original_quantity"] == "accelerance"
    scalar = write_uff(tmp_path / "s.uff", [frf58(F, H, rsp=(1, 0), ref=(1, 0))], SI)
    result = CliRunner().invoke(
        store_app, ["import", str(scalar), *args[2:], "--scalar-direction", "y"]
    )
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout)["direction"] == "y"
