"""Holder–tool clamping models (``joints.holder_tool.model``, contract v1.2): parsing and physics.

The point joint stays the default (every existing request keeps its answer, bit for bit); a
clamping is softer than the composite section with a rigid point joint, a contact softer than
the bonded clamping and tending to it as the interface stiffens; a front gap softens it
further; the contact model turns pressure and roughness into the stated stiffness; a hybrid
assembly on a measured spindle nose gives the analytical answer.
"""

from __future__ import annotations

import numpy as np
import pytest

import rcsa
from rcsa.errors import InputError
from rcsa.model.assembly import assembly_notes, build_model
from rcsa.model.contract import ClampingSpec, parse_assembly
from rcsa.physics.insertion import contact_per_length, contact_stiffness_n_m3
from rcsa.reference import ra1

GRID = {"start_hz": 200.0, "stop_hz": 5000.0, "step_hz": 20.0}


def _doc(holder_tool):
    doc = ra1(GRID)
    if holder_tool is None:
        doc["joints"].pop("holder_tool")
    else:
        doc["joints"]["holder_tool"] = holder_tool
    return doc


def _static(holder_tool) -> float:
    return rcsa.predict(_doc(holder_tool))["static_stiffness_n_m"]


def test_point_is_the_default_and_changes_nothing():
    plain, explicit = rcsa.predict(_doc(ra1()["joints"]["holder_tool"])), rcsa.predict(
        _doc({"model": "point", **ra1()["joints"]["holder_tool"]}))
    assert np.array_equal(plain.tool_point.h, explicit.tool_point.h)


@pytest.mark.parametrize(("holder_tool", "field", "words"), [
    ({"model": "bonded", "stiffness_n_m": 1e7}, "joints.holder_tool.stiffness_n_m", "belongs to the point joint"),
    ({"model": "contact"}, "joints.holder_tool.interface_stiffness_n_m3", "is required"),
    ({"model": "contact", "interface_stiffness_n_m3": 1e14, "contact_pressure_pa": 1e7},
     "joints.holder_tool.interface_stiffness_n_m3", "either"),
    ({"model": "contact", "interface_stiffness_n_m3": 1e20}, "joints.holder_tool.interface_stiffness_n_m3", "<="),
    ({"model": "bonded", "front_gap_length_m": 0.2}, "joints.holder_tool.front_gap_length_m", "leaves no contact"),
    ({"model": "welded"}, "joints.holder_tool.model", "must be one of"),
    ({"model": "point", "interface_stiffness_n_m3": 1e14}, "joints.holder_tool", "interface_stiffness_n_m3"),
])
def test_bad_clamping_fields_are_refused_naming_the_field(holder_tool, field, words):
    with pytest.raises(InputError) as err:
        build_model(parse_assembly(_doc(holder_tool)))
    assert err.value.field.startswith(field) and words in str(err.value), str(err.value)


def test_stiffness_orders_bonded_contact_and_the_front_gap():
    rigid = _static(None)
    bonded = _static({"model": "bonded"})
    stiff_contact = _static({"model": "contact", "interface_stiffness_n_m3": 1e17})
    soft_contact = _static({"model": "contact", "interface_stiffness_n_m3": 1e13})
    gap = _static({"model": "bonded", "front_gap_length_m": 0.01})
    front_only = _static({"model": "bonded", "contact_length_m": 0.02})
    assert rigid > bonded > soft_contact and bonded > gap and bonded > front_only
    assert stiff_contact < bonded and stiff_contact / bonded > 0.99  # in series with a stiff interface


def test_the_contact_model_and_the_interface_per_length():
    assert contact_stiffness_n_m3(5e7, 1e-6) == pytest.approx(5e13)
    via_pressure = parse_assembly(_doc({"model": "contact", "contact_pressure_pa": 5e7, "surface_roughness_m": 1e-6}))
    assert isinstance(via_pressure.holder_tool, ClampingSpec)
    assert via_pressure.holder_tool.interface_stiffness_n_m3 == pytest.approx(5e13)
    # a rigid shank displaced by δ in its bore: normal pressure k_n δ cos θ and shear k_t δ sin θ,
    # projected and integrated over the circumference πr: k_w = π r (k_n + k_t); rotation: π r³ k_t
    kw, kt = contact_per_length(2e14, 1e14, 0.02)
    assert kw == pytest.approx(np.pi * 0.01 * 3e14) and kt == pytest.approx(np.pi * 0.01**3 * 1e14)


def test_a_clamping_needs_the_holders_geometry():
    doc = _doc({"model": "bonded"})
    doc.pop("holder")
    doc["spindle"] = {"measurement_id": "x"}
    spec = parse_assembly(doc)
    with pytest.raises(InputError, match="holder_tip measurement"):
        build_model(spec, "holder_tip")


def test_a_hybrid_bonded_assembly_is_the_analytical_one(tmp_path):
    """RA-1's spindle-nose receptance, stored as a measurement, under the bonded holder and tool
    (its spindle–holder joint kept in the model) = RA-1 bonded, computed analytically."""
    from rcsa.app.measurements import demo_measurement
    from rcsa.app.predictions import predict
    from rcsa.measured.store import MeasurementStore

    store = MeasurementStore(tmp_path / "store")
    mid = store.put(demo_measurement(GRID))
    hybrid_doc = _doc({"model": "bonded"})
    hybrid_doc["spindle"] = {"measurement_id": mid}
    h0 = rcsa.predict(_doc({"model": "bonded"})).tool_point.h
    h1 = predict(hybrid_doc, store=store).tool_point.h
    assert np.max(np.abs(h1 - h0)) / np.max(np.abs(h0)) < 1e-8


def test_wall_ratios_outside_the_calibration_are_noted():
    doc = _doc({"model": "bonded"})
    doc["holder"]["segments"][-1]["outer_diameter_m"] = 0.014  # a 0.7 mm wall around the 12.7 mm shank
    notes = assembly_notes(parse_assembly(doc))
    assert any("outer diameter" in n and "outside the range it was calibrated on" in n for n in notes), notes


def test_a_face_mounted_tool_sits_on_the_holders_face():
    """Nothing inserted (a shell mill on an arbor): no shallow-insertion note; bonded = a rigid face;
    contact = the face's stiffness from the contact annulus (k_r = k_n I, k_t = r_t k_n A)."""
    doc = _doc(None)
    doc["holder"]["segments"] = [{"length_m": 0.04, "outer_diameter_m": 0.063, "material": "steel"},
                                 {"length_m": 0.02, "outer_diameter_m": 0.04, "material": "steel"}]
    doc["tool"] = {"material": "carbide", "diameter_m": 0.05, "shank_diameter_m": 0.04, "overall_length_m": 0.04,
                   "flute_length_m": 0.006, "stickout_m": 0.04}
    rigid = rcsa.predict(doc)
    assert not any("shallow" in n for n in rigid.notes) and any("face-mounted" in n for n in rigid.notes)
    doc["joints"]["holder_tool"] = {"model": "bonded"}
    assert np.array_equal(rcsa.predict(doc).tool_point.h, rigid.tool_point.h)
    doc["joints"]["holder_tool"] = {"model": "contact", "interface_stiffness_n_m3": 5e13}
    spring = build_model(parse_assembly(doc)).holder_tool
    assert spring is not None
    assert spring.rotational_stiffness_nm_rad == pytest.approx(5e13 * np.pi * 0.04**4 / 64)
    assert spring.stiffness_n_m == pytest.approx(5e13 * np.pi * 0.04**2 / 4)
    assert rcsa.predict(doc)["static_stiffness_n_m"] < rigid["static_stiffness_n_m"]


def test_an_arc_of_contact_integrates_the_projected_tractions():
    """Contact over an arc of half-angle α centred on the displacement, by quadrature: k_w = ∫ (k_n cos²θ
    + k_t sin²θ) r dθ; a relative rotation φ slides the surface by u + φ r cos θ, the shank free to slide
    axially (u of least energy), so k_θ = min over u of ∫ k_z (u/φ + r cos θ)² r dθ; a side-lock screw's face
    (area s per length, opposite the arc) adds its normal stiffness and holds the slide. All round and with
    no screw: the full-circle contact of the contact model."""
    from scipy.optimize import minimize_scalar

    from rcsa.model.clamping import arc_per_length

    k_n, k_t, k_z, d = 3e14, 1e14, 2e14, 0.012
    r = d / 2
    for arc, screw in ((360.0, 0.0), (180.0, 0.0), (120.0, 0.0), (120.0, 2e-3), (30.0, 5e-4)):
        theta = np.linspace(-np.radians(arc) / 2, np.radians(arc) / 2, 20001)
        kw_q = np.trapezoid(r * (k_n * np.cos(theta) ** 2 + k_t * np.sin(theta) ** 2), theta) + k_n * screw

        def energy(u, theta=theta, screw=screw):
            return (np.trapezoid(k_z * (u + r * np.cos(theta)) ** 2 * r, theta) + k_z * screw * (u - r) ** 2)

        kt_q = minimize_scalar(energy, bounds=(-2 * r, 2 * r), method="bounded", options={"xatol": 1e-12}).fun
        kw, kt = arc_per_length(k_n, k_t, k_z, d, arc, screw)
        assert kw.real == pytest.approx(kw_q, rel=1e-7) and kt.real == pytest.approx(kt_q, rel=1e-6), (arc, screw)
    kw, kt = arc_per_length(k_n, k_t, k_t, d)
    assert (kw, kt) == pytest.approx(contact_per_length(k_n, k_t, d), rel=1e-14)


def test_a_contact_arc_softens_the_clamping_and_is_bounded():
    full = _static({"model": "bonded", "front_gap_length_m": 0.01})
    arcs = [_static({"model": "bonded", "front_gap_length_m": 0.01, "contact_arc_deg": a}) for a in (240.0, 120.0)]
    assert full > arcs[0] > arcs[1]
    assert np.array_equal(rcsa.predict(_doc({"model": "bonded", "contact_arc_deg": 360.0})).tool_point.h,
                          rcsa.predict(_doc({"model": "bonded"})).tool_point.h)
    with pytest.raises(InputError) as err:
        build_model(parse_assembly(_doc({"model": "bonded", "contact_arc_deg": 5.0})))
    assert err.value.field == "joints.holder_tool.contact_arc_deg"
