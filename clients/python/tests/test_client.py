"""The synchronous client against a real server: every operation once."""

from __future__ import annotations

import pytest

from vigil_client import Vigil, VigilError
from vigil_client.models import PlanRequest, PlanResponse, PositionIn, ScenarioStatus, SensorIn, TargetIn

#: A scenario small enough to register synchronously (see docs/api.md).
SPEC = {
    "name": "pytest corridor",
    "zone": {"width": 200, "height": 100},
    "cell_size": 10,
    "fov": {"shape": "square", "half_width": 15},
    "target_speed": 6,
    "horizon": 3,
    "sources": [
        {"x": -1, "y": 50, "rate": 0.5, "heading": "east"},
        {"x": 100, "y": 101, "rate": 0.3, "heading": "south"},
    ],
}
PLAN = {
    "sensors": [{"id": "a", "x": 55, "y": 55}, {"id": 7, "x": 205, "y": 205}],
    "targets": [{"id": "t1", "x": 120, "y": 140, "vx": 10, "vy": 0}],
    "history": [[{"x": 45, "y": 55}, {"x": 195, "y": 205}]],
}


@pytest.fixture
def vigil(vigil_url: str):
    with Vigil(vigil_url) as client:
        yield client


def assert_legal(plan: PlanResponse, cell_size: float, horizon: int) -> None:
    """Every path has `horizon` cells, each a king move of one cell from the one before."""
    for sensor in plan.plans:
        assert len(sensor.path) == horizon
        previous = sensor.start
        for cell in sensor.path:
            assert max(abs(cell.col - previous.col), abs(cell.row - previous.row)) <= 1
            assert cell.x == pytest.approx((cell.col + 0.5) * cell_size)
            previous = cell


def test_health_and_the_built_ins(vigil: Vigil) -> None:
    assert vigil.health().status == "ok"
    ids = [s.id for s in vigil.list_scenarios().scenarios]
    assert {"paper-v10", "paper-v15", "site-gates", "site-fleet"} <= set(ids)


def test_register_get_list_delete(vigil: Vigil) -> None:
    created = vigil.create_scenario(SPEC)
    assert created.status == ScenarioStatus.READY
    assert (created.grid.cols, created.grid.rows) == (20, 10)
    # Registering the same spec again answers with the same scenario.
    assert vigil.create_scenario(SPEC).id == created.id
    assert vigil.get_scenario(created.id).spec.name == "pytest corridor"
    assert created.id in [s.id for s in vigil.list_scenarios().scenarios]
    vigil.delete_scenario(created.id)
    with pytest.raises(VigilError) as gone:
        vigil.get_scenario(created.id)
    assert gone.value.status == 404


def test_plan_in_a_scenario(vigil: Vigil) -> None:
    plan = vigil.plan("paper-v10", PLAN)
    assert plan.scenario == "paper-v10"
    assert [p.sensor for p in plan.plans] == ["a", 7]  # ids echoed as given
    assert_legal(plan, 10.0, plan.horizon)
    assert plan.expected_detections == pytest.approx(sum(p.expected_detections for p in plan.plans))
    assert plan.expected_detections > 0
    assert plan.bound.upper >= plan.expected_detections - 1e-9


def test_typed_models_send_the_same_request_as_mappings(vigil: Vigil) -> None:
    typed = PlanRequest(
        sensors=[SensorIn(id="a", x=55, y=55), SensorIn(id=7, x=205, y=205)],
        targets=[TargetIn(id="t1", x=120, y=140, vx=10, vy=0)],
        history=[[PositionIn(x=45, y=55), PositionIn(x=195, y=205)]],
    )
    assert typed.to_dict() == PLAN
    by_model = vigil.plan("paper-v10", typed)
    by_mapping = vigil.plan("paper-v10", PLAN)
    assert [[(c.col, c.row) for c in p.path] for p in by_model.plans] == [
        [(c.col, c.row) for c in p.path] for p in by_mapping.plans
    ]
    assert by_model.expected_detections == by_mapping.expected_detections


def test_plan_inline_by_id_and_with_the_scenario(vigil: Vigil) -> None:
    by_id = vigil.plan_inline({"scenario_id": "paper-v10", **PLAN})
    assert by_id.expected_detections == vigil.plan("paper-v10", PLAN).expected_detections
    request = {"scenario": SPEC, "sensors": [{"id": "s", "x": 95, "y": 45}], "horizon": 2}
    inline = vigil.plan_inline(request)
    assert inline.scenario.startswith("s-")
    assert_legal(inline, 10.0, 2)


def test_stats_with_a_sensor_type(vigil: Vigil) -> None:
    default = vigil.stats("site-fleet")
    drone = vigil.stats("site-fleet", "drone")
    assert (default.type_, drone.type_) == ("default", "drone")
    cells = default.cols * default.rows
    assert len(default.lambda_hat) == len(drone.lambda_hat) == cells
    # A drone sees a wider square than a robot, so its cells see more targets.
    assert sum(drone.lambda_hat) > sum(default.lambda_hat)
    with pytest.raises(VigilError) as unknown:
        vigil.stats("site-fleet", "submarine")
    assert unknown.value.status == 404
    assert "submarine" in unknown.value.detail


def test_evaluate_scores_a_plans_own_paths(vigil: Vigil) -> None:
    plan = vigil.plan("paper-v10", PLAN)
    paths = [{"sensor": p.sensor, "path": [{"col": c.col, "row": c.row} for c in p.path]} for p in plan.plans]
    scored = vigil.evaluate("paper-v10", {**PLAN, "paths": paths})
    assert scored.expected_detections == pytest.approx(plan.expected_detections, rel=1e-9)
    inline = vigil.evaluate_inline({"scenario_id": "paper-v10", **PLAN, "paths": paths})
    assert inline.expected_detections == scored.expected_detections


def test_fit_learns_the_rates_of_a_window(vigil: Vigil) -> None:
    step = lambda x: {  # noqa: E731
        "sensors": [{"id": "a", "x": x - 5.0, "y": 95.0}],
        "detections": [{"id": 17, "x": x, "y": 100.0, "vx": 10.0, "vy": 0.0}],
    }
    fitted = vigil.fit("paper-v10", {"steps": [step(60.0), step(70.0)], "prior": "flat"})
    assert (fitted.scenario, fitted.steps, len(fitted.sources)) == ("paper-v10", 2, 8)
    west = fitted.sources[0]
    # One target from the source at (-1, 100): Gamma(2, E), mean 2/E.
    assert west.detected == 1.0
    assert west.rate == pytest.approx(2.0 / west.exposure, rel=1e-9)
    assert west.interval[0] < west.rate < west.interval[1]
    assert fitted.unexplained == []
    with pytest.raises(VigilError) as outside:
        vigil.fit("paper-v10", {"steps": [{"sensors": [{"id": "a", "x": 55.0, "y": 95.0}],
                                           "detections": [{"id": 1, "x": 250.0, "y": 10.0, "vx": 1.0, "vy": 0.0}]}]})
    assert outside.value.status == 422
    assert "steps[0].detections[0]" in outside.value.detail


def test_a_learning_session_reports_its_rates(vigil: Vigil) -> None:
    step = lambda x: {  # noqa: E731
        "sensors": [{"id": "a", "x": x - 5.0, "y": 95.0}],
        "detections": [{"id": 17, "x": x, "y": 100.0, "vx": 10.0, "vy": 0.0}],
    }
    with vigil.session("paper-v10", learn_rates=True) as session:
        session.step(step(60.0))
        response = session.step(step(70.0))
    assert len(response.rates) == 8
    # Target 17 counts once, for the source at (-1, 100).
    assert response.rates[0].detected == 1.0
    assert sum(r.detected for r in response.rates) == 1.0


def test_a_session_steps_and_is_deleted_at_the_end(vigil: Vigil) -> None:
    with vigil.session("paper-v10", horizon=2, history_steps=4) as session:
        assert session.info.step == 0
        sensors = [{"id": "a", "x": 55, "y": 55}, {"id": "b", "x": 245, "y": 245}]
        first = session.step({"sensors": sensors, "detections": [{"id": "t", "x": 60, "y": 70, "vx": 10, "vy": 0}]})
        assert first.step == 0 and first.horizon == 2
        assert_legal(first, 10.0, 2)
        moved = [{"id": p.sensor, "x": p.path[0].x, "y": p.path[0].y} for p in first.plans]
        second = session.step({"sensors": moved}, idempotency_key="second")
        assert second.step == 1
        # Asked again under its key, the step is answered, not made again.
        again = session.step({"sensors": moved}, idempotency_key="second")
        assert again == second
        # Its key with another request is a new step under an old key: refused.
        with pytest.raises(VigilError) as reused:
            session.step({"sensors": [{"id": "a", "x": 5.0, "y": 5.0}]}, idempotency_key="second")
        assert reused.value.status == 422
        info = session.refresh()
        assert info.step == 2 and info.history_held == 2
        assert [t.id for t in info.tracks] == ["t"]
    # The context manager deleted it; deleting again is not an error.
    with pytest.raises(VigilError) as gone:
        session.refresh()
    assert gone.value.status == 404
    session.delete()
