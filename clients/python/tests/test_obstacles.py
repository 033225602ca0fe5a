"""Obstacles in the Stone Soup extra: sight lines, cells per sensor type,
targets stopped by buildings, and moves, each against brute force or a real
server (mostly on the built-in `site-campus`: robots, drones, 8 buildings
and 4 screens)."""

from __future__ import annotations

import datetime
import random
from fractions import Fraction

import numpy as np
import pytest
from stonesoup.types.detection import TrueDetection
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track

from vigil_client import Vigil, VigilError
from vigil_client.stonesoup import (
    IllegalMoveError,
    LatticeActionableMovable,
    Obstacle,
    VigilFOVSensor,
    VigilGroundTruthSimulator,
    VigilMap,
    VigilSensorManager,
    check_actions,
    make_platform,
)

T0 = datetime.datetime(2026, 1, 1)
STEP = datetime.timedelta(seconds=1)


@pytest.fixture(scope="module")
def vigil(vigil_url):
    with Vigil(vigil_url) as client:
        yield client


@pytest.fixture(scope="module")
def campus(vigil):
    return vigil.get_scenario("site-campus").spec.to_dict()


# ---------------------------------------------------------------------------
# Sight: the open segment against a convex polygon's open interior


def hull(points):
    """The convex hull of integer points, counter-clockwise, without
    collinear vertices (Andrew's monotone chain)."""
    pts = sorted(set(points))

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def strictly_inside(poly, x, y, scale=1):
    """Exact open containment of ``(x, y) / scale`` in the counter-clockwise
    ``poly`` (integers, or rationals)."""
    n = len(poly)
    for i in range(n):
        (ax, ay), (bx, by) = poly[i], poly[(i + 1) % n]
        if (bx - ax) * (y - scale * ay) - (by - ay) * (x - scale * ax) <= 0:
            return False
    return True


def brute_blocked(poly, p, q, samples):
    """True when one of the points ``p + k/samples (q - p)``, ``0 < k <
    samples``, strictly inside the segment lies strictly inside the polygon
    (in integers: the points times ``samples``)."""
    dx, dy = q[0] - p[0], q[1] - p[1]
    return any(
        strictly_inside(poly, samples * p[0] + k * dx, samples * p[1] + k * dy, samples)
        for k in range(1, samples)
    )


def witness(poly, p, q):
    """The implementation's blocked part of the segment, checked exactly:
    the midpoint of ``(max(t0, 0), min(t1, 1))`` lies strictly inside."""
    t0, t1 = Obstacle(poly).line_interior(p, (q[0] - p[0], q[1] - p[1]))
    t = (Fraction(max(t0, 0.0)) + Fraction(min(t1, 1.0))) / 2
    return strictly_inside(poly, p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))


def test_sight_is_the_open_segment_rule_against_brute_force():
    """Random convex polygons and segments with integer coordinates: a
    segment the implementation calls clear has no sampled interior point
    strictly inside the polygon, one it calls blocked has a point strictly
    inside (checked in rationals); lines that graze a vertex or run along
    an edge are clear, and the polygon's orientation does not matter."""
    rng = random.Random(7)
    cases = blocked = disagree = 0
    for _ in range(150):
        poly = []
        while len(poly) < 3:
            poly = hull([(rng.randint(0, 20), rng.randint(0, 20)) for _ in range(rng.randint(3, 9))])
        ob, cw = Obstacle(poly), Obstacle(poly[::-1])
        for _ in range(20):
            p = (rng.randint(-6, 26), rng.randint(-6, 26))
            q = (rng.randint(-6, 26), rng.randint(-6, 26))
            if p == q:
                continue
            got = ob.blocks(p, q)
            assert cw.blocks(p, q) == got
            cases += 1
            blocked += got
            if got:
                assert witness(poly, p, q), (poly, p, q)
            if got != brute_blocked(poly, p, q, 64):
                disagree += 1
                # Only a blocked part too short for 64 samples is missed.
                assert got and brute_blocked(poly, p, q, 4096), (poly, p, q)
        n = len(poly)
        for i in range(n):
            u, v, w = poly[i - 1], poly[i], poly[(i + 1) % n]
            # The tangent at v parallel to the chord u-w touches only v.
            d = (w[0] - u[0], w[1] - u[1])
            a, b = (v[0] - 2 * d[0], v[1] - 2 * d[1]), (v[0] + 3 * d[0], v[1] + 3 * d[1])
            assert not ob.blocks(a, b) and not cw.blocks(a, b), (poly, v, "grazes a vertex")
            assert not brute_blocked(poly, a, b, 512)
            # Along the edge v-w, beyond both ends, and the edge itself.
            e = (w[0] - v[0], w[1] - v[1])
            a, b = (v[0] - e[0], v[1] - e[1]), (w[0] + 2 * e[0], w[1] + 2 * e[1])
            assert not ob.blocks(a, b) and not ob.blocks(v, w), (poly, v, w, "along an edge")
            assert not brute_blocked(poly, a, b, 512)
            # From a vertex into or across the interior: blocked; the chord
            # u-w is an edge of a triangle, else a diagonal.
            centroid = (sum(x for x, _ in poly) / n, sum(y for _, y in poly) / n)
            assert ob.blocks(v, centroid) and ob.blocks(centroid, v)
            assert ob.blocks(v, (2 * centroid[0] - v[0], 2 * centroid[1] - v[1]))
            assert ob.blocks(u, w) == (n > 3), (poly, u, w)
            # Ending at a vertex from outside: clear.
            assert not ob.blocks((v[0] + d[0], v[1] + d[1]), v)
            assert not ob.blocks((2 * v[0] - centroid[0], 2 * v[1] - centroid[1]), v)
    assert cases > 2000 and 0.1 * cases < blocked < 0.9 * cases, (cases, blocked)
    assert disagree < 0.02 * cases, (disagree, cases)


def test_the_fov_sensor_sees_along_clear_lines_only():
    """A ground sensor's view stops at a building and a screen (not at a
    grazed corner), an elevated one sees over both, a sensor inside a
    screen sees nothing; Stone Soup coordinates carry the origin."""
    spec = {
        "zone": {"width": 100, "height": 100},
        "cell_size": 10,
        "fov": {"shape": "square", "half_width": 100},
        "sensor_types": {"drone": {"fov": {"shape": "square", "half_width": 100}, "elevated": True}},
        "obstacles": [
            {"polygon": [[40, 40], [60, 40], [60, 60], [40, 60]]},
            {"polygon": [[70, 0], [80, 0], [80, 20]], "kind": "screen"},
        ],
        "target_speed": 10,
        "sources": [{"x": -1, "y": 50, "rate": 0.3}],
    }
    vmap = VigilMap(spec, origin=(1000.0, 2000.0))
    ground = VigilFOVSensor.for_type(vmap)
    drone = VigilFOVSensor.for_type(vmap, "drone")
    assert not ground.elevated and drone.elevated

    def at(x, y):
        return (1000.0 + x, 2000.0 + y)

    here = at(15, 15)
    assert not ground.covers_at(here, at(85, 85))  # behind the building
    assert drone.covers_at(here, at(85, 85))
    assert not vmap.sees("default", here, at(85, 85)) and vmap.sees("drone", here, at(85, 85))
    assert not vmap.clear(here, at(85, 85)) and vmap.clear(here, at(30, 90))
    assert ground.covers_at(here, at(30, 90))  # beside it
    assert ground.covers_at(here, at(65, 35)) and ground.covers_at(here, at(35, 65))
    # The line from (15, 15) through the corner (40, 60) grazes it; a unit
    # further east it cuts the corner off.
    assert ground.covers_at(here, at(45, 69)) and ground.covers_at(here, at(44, 69))
    assert not ground.covers_at(here, at(46, 69))
    assert ground.covers_at(at(40, 30), at(40, 70))  # along the west wall
    assert not ground.covers_at(at(40, 30), at(41, 70))
    assert not ground.covers_at(at(65, 5), at(95, 5))  # through the screen
    assert drone.covers_at(at(65, 5), at(95, 5))
    inside = at(77, 5)  # in the screen: sees nothing, not even beside itself
    assert not ground.covers_at(inside, at(77, 6)) and not ground.covers_at(inside, at(40, 5))
    assert drone.covers_at(inside, at(40, 5))
    # measure() detects exactly the targets in clear view.
    from stonesoup.types.groundtruth import GroundTruthState

    truths = {GroundTruthState([x + 1000.0, 0, y + 2000.0, 0], timestamp=T0)
              for x, y in [(85, 85), (30, 90), (65, 35), (95, 95)]}
    platform = make_platform("g", here, T0, vmap)
    seen = {tuple(d.groundtruth_path.state_vector.ravel()[[0, 2]]) for d in platform.sensors[0].measure(truths)}
    assert seen == {(1030.0, 2090.0), (1065.0, 2035.0)}
    # A ground type cannot stand in the building; the screen does not block cells.
    assert not vmap.is_free((4, 4)) and vmap.is_free((4, 4), "drone") and vmap.is_free((7, 0))
    with pytest.raises(ValueError, match="building"):
        make_platform("g", at(45, 45), T0, vmap)


def test_obstacles_are_validated_and_either_orientation_is_one_polygon():
    square = [(0, 0), (2, 0), (2, 2), (0, 2)]
    for given in (square, square[::-1]):
        v = Obstacle(given).vertices
        area = sum(v[i - 1][0] * v[i][1] - v[i][0] * v[i - 1][1] for i in range(len(v))) / 2
        assert set(v) == set(square) and area == 4.0  # kept counter-clockwise
    assert Obstacle(square[::-1]).contains_open((1, 1)) and not Obstacle(square).contains_open((2, 1))
    assert Obstacle(square).contains_closed((2, 1)) and not Obstacle(square).contains_closed((2.001, 1))
    assert Obstacle(square).stop((-1, 1), (1, 0)) == 1.0 and Obstacle(square).stop((1, 1), (1, 0)) == 0.0
    assert Obstacle(square).stop((-1, 2), (1, 0)) == float("inf")  # along the top edge
    for bad, match in [([(0, 0), (2, 0), (1, 1), (2, 2), (0, 2)], "convex"),
                       ([(0, 0), (1, 0), (2, 0), (1, 1)], "collinear"),
                       ([(0, 0), (1, 0)], "3 vertices"),
                       ([(0, 0), (1, 0), (0, 0), (0, 1)], "repeated")]:
        with pytest.raises(ValueError, match=match):
            Obstacle(bad)
    spec = {"zone": {"width": 10, "height": 10}, "cell_size": 1, "fov": {"shape": "square", "half_width": 1},
            "obstacles": [{"polygon": square, "kind": "wall"}]}
    with pytest.raises(ValueError, match=r"obstacles\[0\]: unknown obstacle kind 'wall'"):
        VigilMap(spec)


# ---------------------------------------------------------------------------
# Cells per sensor type, against the server


def test_cells_per_type_agree_with_the_server(vigil, campus):
    """On site-campus: every cell whose centre lies in a building is refused
    to a robot (422 naming sensors[0]) and accepted for a drone; every free
    cell beside a building is accepted for a robot; the map's free cells are
    a brute-force count of cell centres in no closed building."""
    vmap = VigilMap(campus)
    robot, drone = set(vmap.free_cells("robot")), set(vmap.free_cells("drone"))
    assert set(vmap.free_cells()) == robot  # default is the ground robot
    every = {(c, r) for r in range(vmap.rows) for c in range(vmap.cols)}
    assert drone == every
    buildings = [o for o in campus["obstacles"] if o.get("kind", "building") == "building"]

    def in_closed(poly, x, y):
        # Either orientation: all edge cross products of one sign (or 0).
        n = len(poly)
        s = [(poly[(i + 1) % n][0] - poly[i][0]) * (y - poly[i][1])
             - (poly[(i + 1) % n][1] - poly[i][1]) * (x - poly[i][0]) for i in range(n)]
        return all(v >= -1e-6 for v in s) or all(v <= 1e-6 for v in s)

    brute = {c for c in every
             if not any(in_closed(o["polygon"], (c[0] + 0.5) * 10, (c[1] + 0.5) * 10) for o in buildings)}
    assert robot == brute
    assert (2, 16) not in robot  # its centre (25, 165) is on the gatehouse's south wall
    assert 150 < len(every - robot) < 400

    def plan(cell, type_name):
        x, y = vmap.centre(cell)
        return vigil.plan("site-campus", {"sensors": [{"id": "s", "x": x, "y": y, "type": type_name}],
                                          "horizon": 1})

    for cell in sorted(every - robot):
        with pytest.raises(VigilError) as refused:
            plan(cell, "robot")
        assert refused.value.status == 422 and "sensors[0]" in refused.value.detail, cell
    for cell in sorted(every - robot)[::7]:
        plan(cell, "drone")
    beside = sorted(c for c in robot if vmap.reachable(c, 1, "drone").keys() - robot)
    assert len(beside) > 50
    for cell in beside:
        plan(cell, "robot")


def test_a_ground_sensor_never_crosses_a_building(vigil):
    """A wall of building cells: a ground type of speed 2 cannot cross it in
    a step (VigilMap and the server's evaluate agree), an elevated one can."""
    spec = {
        "zone": {"width": 100, "height": 100},
        "cell_size": 10,
        "fov": {"shape": "square", "half_width": 20},
        "sensor_speed": 2,
        "sensor_types": {"drone": {"fov": {"shape": "square", "half_width": 20}, "speed": 2,
                                   "elevated": True}},
        "obstacles": [{"polygon": [[44, -10], [46, -10], [46, 110], [44, 110]]}],
        "target_speed": 10,
        "sources": [{"x": -1, "y": 50, "rate": 0.3}],
    }
    sid = vigil.create_scenario(spec).id
    vmap = VigilMap(vigil.get_scenario(sid).spec.to_dict())
    c = vmap.centre
    assert vmap.check_move(c((3, 5)), c((5, 5)), type_name="drone") == (5, 5)
    with pytest.raises(IllegalMoveError, match="more than 2 king move"):
        vmap.check_move(c((3, 5)), c((5, 5)))
    with pytest.raises(IllegalMoveError, match="building"):
        vmap.check_move(c((3, 5)), c((4, 5)))

    def evaluate(type_name, cell):
        return vigil.evaluate(sid, {"sensors": [{"id": "s", "x": 35, "y": 55, "type": type_name}],
                                    "paths": [{"sensor": "s", "path": [{"col": cell[0], "row": cell[1]}]}],
                                    "horizon": 1})

    evaluate("drone", (5, 5))
    evaluate("default", (2, 7))
    with pytest.raises(VigilError) as refused:
        evaluate("default", (5, 5))
    assert refused.value.status == 422 and "paths[0]" in refused.value.detail
    gen = next(iter(make_platform("r", c((3, 5)), T0, vmap).actions(T0 + STEP)))
    assert {tuple(vmap.cell_of(a.target_value.ravel()[:2])) for a in gen} == set(vmap.reachable((3, 5)))
    assert all(cell[0] < 4 for cell in vmap.reachable((3, 5)))
    gen = next(iter(make_platform("d", c((3, 5)), T0, vmap, "drone").actions(T0 + STEP)))
    assert len(list(gen)) == 25
    vigil.delete_scenario(sid)


# ---------------------------------------------------------------------------
# Targets that end at buildings, and what a sensor sees of them


def test_the_population_among_buildings_is_the_models(vigil, campus):
    """site-campus over 200 seeds: the mean number of targets in the zone at
    the first step (the stationary start) and at the sixth (after five
    steps of emissions) is the server's expected_targets_in_zone within 4
    standard errors; no target is ever inside a building."""
    expected = vigil.get_scenario("site-campus").summary.expected_targets_in_zone
    # Without the buildings' stops the site-gates yard holds far more.
    assert expected < 0.8 * vigil.get_scenario("site-gates").summary.expected_targets_in_zone
    vmap = VigilMap(campus)
    buildings = [o for o in vmap.obstacles if o.is_building]
    first, sixth = [], []
    for k in range(200):
        sim = VigilGroundTruthSimulator(spec=campus, initial_time=T0, number_steps=6, seed=k)
        counts = []
        for _, paths in sim:
            counts.append(len(paths))
            if k < 20:
                for path in paths:
                    x, _, y, _ = path.state.state_vector.ravel()
                    assert not any(b.contains_open((x, y)) for b in buildings), (x, y)
        first.append(counts[0])
        sixth.append(counts[-1])
    for counts in (np.array(first), np.array(sixth)):
        standard_error = counts.std(ddof=1) / np.sqrt(len(counts))
        assert abs(counts.mean() - expected) < 4 * standard_error, (counts.mean(), expected, standard_error)


def test_what_a_sensor_sees_is_the_servers_d_hat(vigil, campus):
    """The mean number of stationary targets a VigilFOVSensor of each type
    has in clear view from a cell, over 200 seeds, is the server's d_hat of
    that cell and type within 4 standard errors: a robot by the north-east
    hedge (which hides most of its targets), one by the main hall, one
    inside the copse (sees nothing), and drones (see over everything)."""
    vmap = VigilMap(campus)
    stats = {t: vigil.stats("site-campus", t) for t in ("robot", "drone")}
    looks = [("robot", (30, 25)), ("robot", (5, 17)), ("robot", (15, 12)), ("drone", (19, 3)), ("drone", (6, 18))]
    sensors = {t: VigilFOVSensor.for_type(vmap, t) for t in stats}
    counts = {look: [] for look in looks}
    in_fov = []
    for k in range(200):
        sim = VigilGroundTruthSimulator(spec=campus, initial_time=T0, number_steps=1, seed=k)
        _, paths = next(iter(sim))
        points = [p.state.state_vector.ravel()[[0, 2]] for p in paths]
        for t, cell in looks:
            counts[(t, cell)].append(sum(sensors[t].covers_at(vmap.centre(cell), q) for q in points))
        in_fov.append(sum(vmap.sensor_type("robot").covers(vmap.centre((30, 25)), q) for q in points))
    for (t, cell), c in counts.items():
        c = np.array(c)
        d_hat = stats[t].d_hat[cell[1] * vmap.cols + cell[0]]
        if d_hat == 0.0:
            assert not c.any(), (t, cell)
            continue
        standard_error = c.std(ddof=1) / np.sqrt(len(c))
        assert abs(c.mean() - d_hat) < 4 * standard_error, (t, cell, c.mean(), d_hat, standard_error)
    assert stats["robot"].d_hat[12 * vmap.cols + 15] == 0.0  # the copse
    # The hedge hides most of the robot's targets: sight matters there.
    assert np.mean(counts[("robot", (30, 25))]) < 0.6 * np.mean(in_fov)


# ---------------------------------------------------------------------------
# A managed run: robots keep off buildings, drones fly over them


def test_a_managed_run_on_the_campus_moves_legally(vigil, campus):
    """Two robots and a drone on site-campus, planned by Vigil with tracks
    from what their sensors see: every move is legal for its type, no robot
    ever stands on a building's cell, and the platforms move."""
    vmap = VigilMap(campus)
    types = {"d1": "drone", "r1": "robot", "r2": "robot"}
    starts = {"d1": (65, 185), "r1": (55, 175), "r2": (135, 125)}  # d1 above the main hall
    platforms = [make_platform(pid, starts[pid], T0, vmap, types[pid], sensor_kwargs={"seed": i})
                 for i, pid in enumerate(sorted(types))]
    manager = VigilSensorManager(vigil=vigil, scenario_id="site-campus", platforms=set(platforms),
                                 sensor_types=types)
    sim = VigilGroundTruthSimulator(spec=campus, initial_time=T0, number_steps=12, seed=3)
    buildings = [o for o in vmap.obstacles if o.is_building]
    tracks: dict[str, Track] = {}
    moved, detected, drone_on_building = 0, 0, False
    try:
        for now, truths in sim:
            if now > T0:
                for p in platforms:
                    p.act(now)
            for p in platforms:
                xy = p.position.ravel()[:2]
                on_building = any(b.contains_closed(xy) for b in buildings)
                assert not (on_building and types[p.id] == "robot"), (p.id, xy)
                drone_on_building |= on_building
                for det in p.sensors[0].measure({t.state for t in truths}):
                    assert isinstance(det, TrueDetection)
                    sv = det.groundtruth_path.state_vector.ravel()
                    assert p.sensors[0].covers_at(xy, sv[[0, 2]])
                    detected += 1
                    tid = det.groundtruth_path.metadata["path_id"]
                    tracks.setdefault(tid, Track(id=tid)).append(
                        GaussianState(sv, np.eye(4), timestamp=now))
            config = manager.choose_actions(set(tracks.values()), now + STEP)[0]
            check_actions(config, vmap, speeds=None)  # the movables' types
            check_actions(config, vmap, speeds=None, types=types)
            for p, actions in config.items():
                (action,) = actions
                start = vmap.cell_of(p.position.ravel()[:2])
                end = vmap.cell_of(action.target_value.ravel()[:2])
                assert vmap.is_free(end, types[p.id])
                assert end in vmap.reachable(start, type_name=types[p.id])
                moved += end != start
                p.add_actions(actions)
    finally:
        manager.close()
    assert moved > 0 and detected > 0 and drone_on_building


def test_the_manager_refuses_what_obstacles_rule_out(vigil, campus):
    vmap = VigilMap(campus)
    drone = make_platform("d1", (65, 185), T0, vmap, "drone")
    assert isinstance(drone.movement_controller, LatticeActionableMovable)
    assert drone.movement_controller.type_name == "drone"
    # Planned as the default (ground) type while it moves as a drone.
    manager = VigilSensorManager(vigil=vigil, scenario_id="site-campus", platforms={drone})
    with pytest.raises(ValueError, match="sensor_types"):
        manager.choose_actions(set(), T0 + STEP)
    with pytest.raises(ValueError, match="paper"):
        VigilSensorManager(vigil=vigil, scenario_id="site-campus", platforms={drone},
                           sensor_types={"d1": "drone"}, plan_options={"estimator": "paper"})
    with pytest.raises(ValueError, match="building"):
        make_platform("r1", (65, 185), T0, vmap, "robot")
    with pytest.raises(IllegalMoveError, match="building"):
        vmap.check_move(vmap.centre((5, 17)), vmap.centre((6, 18)), type_name="robot")
    assert vmap.check_move(vmap.centre((5, 17)), vmap.centre((6, 18)), type_name="drone") == (6, 18)
