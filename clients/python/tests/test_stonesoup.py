"""The Stone Soup extra: VigilSensorManager, the move checks, the ground truth.

Runs a short version of examples/stonesoup/compare.py (two platforms, ten
steps, a fixed seed) against a real server. CI installs the extra, so these
tests run there.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.util
import pathlib

import numpy as np
import pytest

from vigil_client import Vigil
from vigil_client.stonesoup import (
    IllegalMoveError,
    VigilGroundTruthSimulator,
    VigilMap,
    VigilSensorManager,
    make_platform,
)

ROOT = pathlib.Path(__file__).resolve().parents[3]
T0 = datetime.datetime(2026, 1, 1)
STEP = datetime.timedelta(seconds=1)


def load_example():
    path = ROOT / "examples" / "stonesoup" / "compare.py"
    spec = importlib.util.spec_from_file_location("stonesoup_compare", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def vigil(vigil_url):
    with Vigil(vigil_url) as client:
        yield client


@pytest.fixture(scope="module")
def paper(vigil):
    return vigil.get_scenario("paper-v10").spec.to_dict()


def test_vigil_manager_moves_legally_and_detects_at_least_as_many_as_random(vigil, paper):
    compare = load_example()
    vmap = VigilMap(paper)
    steps, seed = 10, 0
    truth = compare.ground_truth(paper, steps, seed)
    args = argparse.Namespace(seed=seed, scenario="paper-v10")
    # run() checks every move of every decision with check_actions (an
    # IllegalMoveError fails the test) and that no platform is left out.
    runs = {name: compare.run(name, 2, truth, vmap, args, vigil) for name in ("vigil", "random")}
    for r in runs.values():
        assert r["moves_checked"] == 2 * (steps - 1)
        assert len(r["per_step"]) == steps
    v, rnd = runs["vigil"], runs["random"]
    assert sum(v["per_step"]) >= sum(rnd["per_step"]), (v, rnd)
    assert v["detected_once"] >= rnd["detected_once"], (v, rnd)


def test_every_vigil_move_is_a_legal_king_move_of_the_type(vigil, paper):
    """Platforms of site-fleet's fleet (drones of speed 3 among no-go
    ground), planned through a session: each move ends on a free cell centre
    within the type's speed."""
    spec = vigil.get_scenario("site-fleet").spec.to_dict()
    vmap = VigilMap(spec)
    types = {"d1": "drone", "r1": "robot", "r2": "robot"}
    starts = {"d1": (105, 205), "r1": (255, 85), "r2": (125, 95)}
    platforms = [make_platform(pid, starts[pid], T0, vmap, types[pid]) for pid in types]
    manager = VigilSensorManager(vigil=vigil, scenario_id="site-fleet", platforms=set(platforms),
                                 sensor_types=types, use_session=True)
    sim = VigilGroundTruthSimulator(spec=spec, initial_time=T0, number_steps=6, seed=5)
    moved = 0
    try:
        for now, _ in sim:
            if now > T0:
                for p in platforms:
                    p.act(now)
            config = manager.choose_actions(set(), now + STEP)[0]
            assert set(config) == set(platforms)
            for p, actions in config.items():
                (action,) = actions
                start = vmap.cell_of(p.position.ravel()[:2])
                end = vmap.cell_of(action.target_value.ravel()[:2])
                speed = vmap.sensor_type(types[p.id]).speed
                assert vmap.is_free(end)
                assert np.allclose(vmap.centre(end), action.target_value.ravel()[:2])
                assert max(abs(end[0] - start[0]), abs(end[1] - start[1])) <= speed
                moved += end != start
                p.add_actions(actions)
    finally:
        manager.close()
    assert moved > 0, "no platform ever moved"


def test_check_move_refuses_what_a_vigil_sensor_cannot_do(vigil):
    vmap = VigilMap(vigil.get_scenario("site-fleet").spec.to_dict())
    c = vmap.centre
    assert vmap.check_move(c((5, 5)), c((6, 6)), 1) == (6, 6)  # a diagonal king move
    assert vmap.check_move(c((5, 5)), c((8, 2)), 3) == (8, 2)
    with pytest.raises(IllegalMoveError, match="more than 1 king move"):
        vmap.check_move(c((5, 5)), c((7, 5)), 1)
    with pytest.raises(IllegalMoveError, match="no-go"):
        vmap.check_move(c((13, 9)), c((14, 10)), 1)  # (145, 105) is in the no-go [140,240]x[100,170]
    with pytest.raises(IllegalMoveError, match="outside the zone"):
        vmap.check_move(c((0, 0)), np.array([-5.0, 5.0]), 1)
    with pytest.raises(IllegalMoveError, match="not the centre"):
        vmap.check_move(c((5, 5)), c((6, 6)) + 1.0, 1)
    # Across no-go ground: (15, 8) -> (15, 12) is 4 rows, more than 3 king
    # moves even before the blocked cells between.
    with pytest.raises(IllegalMoveError):
        vmap.check_move(c((15, 8)), c((15, 12)), 3)


def test_manager_refuses_random_ids_and_wrong_steps(vigil, paper):
    vmap = VigilMap(paper)
    p = make_platform("p1", (75, 75), T0, vmap)
    manager = VigilSensorManager(vigil=vigil, scenario_id="paper-v10", platforms={p})
    with pytest.raises(ValueError, match="time_step"):
        manager.choose_actions(set(), T0 + 2 * STEP)
    with pytest.raises(ValueError, match="nchoose"):
        manager.choose_actions(set(), T0 + STEP, nchoose=2)
    anonymous = make_platform("0b5a2f4e-3c1d-4e8f-9a7b-6c5d4e3f2a1b", (75, 75), T0, vmap)
    manager = VigilSensorManager(vigil=vigil, scenario_id="paper-v10", platforms={anonymous})
    with pytest.raises(ValueError, match="explicit id"):
        manager.choose_actions(set(), T0 + STEP)


def test_tracks_and_looks_reach_the_plan_request(vigil, paper):
    from stonesoup.types.state import GaussianState
    from stonesoup.types.track import Track

    vmap = VigilMap(paper, origin=(1000.0, 2000.0))
    p = make_platform("p1", (1075, 2075), T0, vmap)
    manager = VigilSensorManager(vigil=vigil, scenario_id="paper-v10", platforms={p},
                                 origin=(1000.0, 2000.0))
    track = Track([GaussianState([1070.0, 10.0, 2080.0, -5.0], np.eye(4), timestamp=T0)], id="k")
    old = Track([GaussianState([1070.0, 1.0, 2080.0, 0.0], np.eye(4),
                               timestamp=T0 - 17 * STEP)], id="old")
    request = manager.plan_request({track, old}, T0 + STEP)
    assert request["sensors"] == [{"id": "p1", "x": 75.0, "y": 75.0, "type": "default"}]
    assert request["targets"] == [{"id": "k", "x": 70.0, "y": 80.0, "vx": 10.0, "vy": -5.0}]
    assert "history" not in request
    (config,) = manager.choose_actions({track}, T0 + STEP)
    p.add_actions(config[p])
    p.act(T0 + STEP)
    request = manager.plan_request({track}, T0 + 2 * STEP)
    assert request["history"] == [[{"x": 75.0, "y": 75.0, "type": "default"}]]
    # The track moved on at its velocity for one step.
    assert request["targets"][0]["x"] == pytest.approx(80.0)
    assert request["targets"][0]["y"] == pytest.approx(75.0)


def test_a_learning_manager_reports_the_rates_it_learns(vigil, paper):
    from stonesoup.types.state import GaussianState
    from stonesoup.types.track import Track

    vmap = VigilMap(paper)
    p = make_platform("p1", (55, 95), T0, vmap)
    with pytest.raises(ValueError, match="use_session"):
        VigilSensorManager(vigil=vigil, scenario_id="paper-v10", platforms={p}, learn_rates=True)
    manager = VigilSensorManager(vigil=vigil, scenario_id="paper-v10", platforms={p},
                                 use_session=True, learn_rates=True)
    # A track flying east along y = 100, from the source at (-1, 100).
    track = Track([GaussianState([60.0, 10.0, 100.0, 0.0], np.eye(4), timestamp=T0)], id="k")
    try:
        manager.choose_actions({track}, T0 + STEP)
    finally:
        manager.close()
    rates = manager.last_response.rates
    assert len(rates) == 8
    assert rates[0].detected == 1.0 and rates[0].exposure > 0


@pytest.mark.parametrize("scenario", ["paper-v10", "site-gates"])
def test_the_stationary_population_is_the_models(vigil, scenario):
    """The first step's count, over independent seeds, has the mean of the
    server's expected_targets_in_zone (site-gates: directed cones and speed
    mixtures), within 4 standard errors of the sample mean."""
    found = vigil.get_scenario(scenario)
    spec, expected = found.spec.to_dict(), found.summary.expected_targets_in_zone
    counts = np.array([
        len(next(iter(VigilGroundTruthSimulator(spec=spec, initial_time=T0, number_steps=1, seed=k)))[1])
        for k in range(200)
    ])
    standard_error = counts.std(ddof=1) / np.sqrt(len(counts))
    assert abs(counts.mean() - expected) < 4 * standard_error, (counts.mean(), expected, standard_error)


def test_ground_truth_paths_fly_straight_inside_the_zone(paper):
    sim = VigilGroundTruthSimulator(spec=paper, initial_time=T0, number_steps=100, seed=11)
    paths = {}
    for _, truths in sim:
        for path in truths:
            paths[path.id] = path
            x, _, y, _ = path.state.state_vector.ravel()
            assert 0 <= x <= 300 and 0 <= y <= 300
    assert len(paths) > 100
    for path in paths.values():
        svs = np.array([s.state_vector.ravel() for s in path.states])
        speed = np.hypot(svs[:, 1], svs[:, 3])
        assert np.allclose(speed, 10.0)  # the scenario's target speed, constant
        assert np.allclose(np.diff(svs[:, 0]), svs[0, 1]) and np.allclose(np.diff(svs[:, 2]), svs[0, 3])
        steps = [(s.timestamp - T0) / STEP for s in path.states]
        assert steps == list(range(int(steps[0]), int(steps[0]) + len(steps)))  # no gaps: in, then out
