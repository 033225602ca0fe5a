"""Ground truth that follows Vigil's target model:
:class:`VigilGroundTruthSimulator` (targets born at the scenario's sources
outside the zone that fly straight and leave, or end at a building).
"""

from __future__ import annotations

import datetime
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from stonesoup.base import Property
from stonesoup.buffered_generator import BufferedGenerator
from stonesoup.simulator.base import GroundTruthSimulator
from stonesoup.types.array import StateVector
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState

from ._map import VigilMap

_HEADING_DEGREES = {"east": 0.0, "north": 90.0, "west": 180.0, "south": 270.0}


@dataclass
class _Flight:
    path: GroundTruthPath
    pos: np.ndarray  # Vigil coordinates
    vel: np.ndarray  # per step
    leave: float  # distance from the source at which it leaves the zone
    flown: float  # distance flown from the source
    stop: float = math.inf  # distance from the source at which a building ends its flight


class VigilGroundTruthSimulator(GroundTruthSimulator):
    """Targets as Vigil's model has them, as Stone Soup ground truth.

    Each source of the scenario ``spec`` (outside the zone) emits targets
    as a Poisson process of ``rate`` per step in continuous time: per step
    a Poisson count, each emitted at a uniform time within the step. Each
    target draws, once, a takeoff angle uniform over the source's cone
    (``direction +- spread/2`` degrees counter-clockwise from east, the
    heading's direction when ``direction`` is absent, spread 180 by default)
    and a speed from the source's ``speeds`` (weights normalised;
    ``target_speed`` without them), then flies straight at that speed.
    A target's flight ends where its ray first enters a building's
    interior (the spec's ``obstacles`` of kind ``building``; screens do not
    stop targets): from there on it is gone, as if it had left the zone.
    A target exists while inside the closed zone and before that point:
    its :class:`GroundTruthPath` (id ``"t<n>"``, states ``[x, vx, y, vy]``
    in Stone Soup coordinates, velocities per second) has a state at every
    step it is inside (each state's ``metadata["path_id"]`` is the path's
    id); it is dropped once it leaves or is stopped. Targets whose ray
    misses the zone, or meets a building before it, never appear.

    With ``stationary_start`` (default) the first step already holds the
    stationary population (targets emitted over a window long enough for
    any to have crossed the zone), as if the process had always run.
    Yields ``(time, set of paths in the zone)`` for ``number_steps`` steps.
    """

    spec: Mapping[str, Any] = Property(doc="The scenario spec (GET /v1/scenarios/{id}'s spec).")
    initial_time: datetime.datetime = Property(doc="Time of the first step.")
    number_steps: int = Property(default=100, doc="Steps to yield.")
    timestep: datetime.timedelta = Property(
        default=datetime.timedelta(seconds=1), doc="Stone Soup time of one Vigil step."
    )
    seed: int = Property(default=None, doc="Seed of the target stream.")
    origin: tuple = Property(default=(0.0, 0.0), doc="Stone Soup coordinates of Vigil's (0, 0).")
    stationary_start: bool = Property(default=True, doc="Start from the stationary population.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.map = VigilMap(self.spec, self.origin)
        self._sources = [self._source(i, s) for i, s in enumerate(self.spec["sources"])]
        self._count = 0

    def _source(self, i: int, s: Mapping[str, Any]) -> dict:
        w, h = self.map.width, self.map.height
        x, y = float(s["x"]), float(s["y"])
        if s.get("direction") is not None:
            centre = float(s["direction"])
        else:
            heading = s.get("heading") or _infer_heading(x, y, w, h)
            if heading is None:
                raise ValueError(f"sources[{i}]: needs a heading or a direction")
            centre = _HEADING_DEGREES[heading]
        if s.get("speeds"):
            speeds = [float(v["speed"]) for v in s["speeds"]]
            weights = np.array([float(v["weight"]) for v in s["speeds"]])
        else:
            speeds, weights = [float(self.spec["target_speed"])], np.ones(1)
        reach = max(math.hypot(cx - x, cy - y) for cx in (0.0, w) for cy in (0.0, h))
        return {
            "pos": np.array([x, y]),
            "rate": float(s["rate"]),
            "centre": math.radians(centre),
            "spread": math.radians(float(s.get("spread") or 180.0)),
            "speeds": speeds,
            "weights": weights / weights.sum(),
            "reach": reach,
        }

    def _emit(self, src: dict, window: float, rng: np.random.Generator) -> list[_Flight]:
        out = []
        for _ in range(rng.poisson(src["rate"] * window)):
            age = rng.random() * window
            angle = src["centre"] + (rng.random() - 0.5) * src["spread"]
            speed = src["speeds"][rng.choice(len(src["speeds"]), p=src["weights"])]
            u = np.array([math.cos(angle), math.sin(angle)])
            span = _ray_in_zone(src["pos"], u, self.map.width, self.map.height)
            if span is None:
                continue  # its ray misses the zone: it never appears
            stop = self.map.flight_stop(src["pos"], u)
            if stop <= span[0]:
                continue  # a building ends its flight before the zone
            flown = speed * age
            if flown >= stop:
                continue  # stopped already (emitted before the first step)
            self._count += 1
            out.append(_Flight(GroundTruthPath(id=f"t{self._count}"),
                               src["pos"] + u * flown, u * speed, span[1], flown, stop))
        return out

    @BufferedGenerator.generator_method
    def groundtruth_paths_gen(self):
        rng = np.random.default_rng(self.seed)
        self._count = 0
        dt = self.timestep.total_seconds()
        flights: list[_Flight] = []
        if self.stationary_start:
            for src in self._sources:
                slowest = min(src["speeds"])
                flights += self._emit(src, src["reach"] / slowest, rng)
        time = self.initial_time
        for step in range(self.number_steps):
            if step > 0:
                time += self.timestep
                for f in flights:
                    f.pos = f.pos + f.vel
                    f.flown += float(np.hypot(*f.vel))
                flights = [f for f in flights if f.flown <= f.leave + 1e-9 and f.flown < f.stop]
                for src in self._sources:
                    flights += self._emit(src, 1.0, rng)
            current = set()
            for f in flights:
                if 0.0 <= f.pos[0] <= self.map.width and 0.0 <= f.pos[1] <= self.map.height:
                    x, y = self.map.from_vigil(f.pos)
                    f.path.append(GroundTruthState(
                        StateVector([x, f.vel[0] / dt, y, f.vel[1] / dt]), timestamp=time,
                        metadata={"path_id": f.path.id}))
                    current.add(f.path)
            yield time, current


def _infer_heading(x: float, y: float, w: float, h: float) -> str | None:
    """The heading of a source beside exactly one edge of ``[0,w]x[0,h]``."""
    found = [hd for cond, hd in (
        (x < 0 and 0 <= y <= h, "east"), (x > w and 0 <= y <= h, "west"),
        (y < 0 and 0 <= x <= w, "north"), (y > h and 0 <= x <= w, "south"))if cond]
    return found[0] if len(found) == 1 else None


def _ray_in_zone(p: np.ndarray, u: np.ndarray, w: float, h: float):
    """``(t0, t1)``, the distances along the ray ``p + t u`` (t >= 0) inside
    the closed zone ``[0,w]x[0,h]``, or None when it misses."""
    t0, t1 = 0.0, math.inf
    for o, d, lo, hi in ((p[0], u[0], 0.0, w), (p[1], u[1], 0.0, h)):
        if abs(d) < 1e-15:
            if o < lo or o > hi:
                return None
            continue
        a, b = (lo - o) / d, (hi - o) / d
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
    return (t0, t1) if t0 <= t1 else None
