"""POST /v1/identifications and /v1/effects on a measured spindle of the service's store."""

from __future__ import annotations

from rcsa.measured.store import Measurement, MeasurementMeta, MeasurementStore
from rcsa.model.assembly import build_model
from rcsa.physics.elimination import tip_receptance
from rcsa.reference import ra1
from tests.analysis.test_hybrid_analyses import BAND, SPEC, F, W, _point, assert_accurate, request

from .conftest import READ, assert_problem


def test_rest_identification_and_effects_read_the_service_store(make_client, store_path):
    st = MeasurementStore(store_path)
    s = tip_receptance(build_model(SPEC).spindle, W)
    mid = st.put(Measurement(F, _point(s), MeasurementMeta("ra1", "x", "spindle_nose", "point_receptance")))
    tip = st.put(Measurement(F, _point(tip_receptance(build_model(SPEC).to_holder_tip(), W)),
                             MeasurementMeta("ra1", "x", "holder_tip", "point_receptance")))
    with make_client() as client:
        r = client.post("/v1/identifications", json=request(mid), headers=READ)
        assert r.status_code == 200, r.text
        assert_accurate(r.json())
        r = client.post("/v1/effects", json={"assembly": {**ra1(BAND), "spindle": {"measurement_id": mid}},
                                             "parameters": ["holder_tool.stiffness_n_m"]}, headers=READ)
        assert r.status_code == 200 and r.json()["modes_method"] == "modal_fit"
        r = client.post("/v1/identifications", headers=READ,
                        json=request(tip, holder=False, bounds={"spindle_holder.damping_ns_m": [10.0, 1e4]}))
        assert "holder_tip" in assert_problem(r, 422, "bounds.spindle_holder.damping_ns_m")["detail"]
        r = client.post("/v1/effects", headers=READ, json={"assembly": {**ra1(BAND), "spindle": {
            "measurement_id": mid}}, "parameters": ["bearings[1].damping_ns_m"]})
        assert_problem(r, 422, "parameters")


