"""Vigil as a Stone Soup sensor manager (the ``stonesoup`` extra).

Install with ``pip install './clients/python[stonesoup]'`` (Stone Soup 1.9.1
or later 1.x). This module is imported only by users of the extra; the rest
of :mod:`vigil_client` never imports it.

What it provides
----------------
* :class:`VigilSensorManager`, a Stone Soup
  :class:`~stonesoup.sensormanager.base.SensorManager`: ``choose_actions``
  sends the platforms' positions (and their Vigil sensor types), the tracks'
  positions and velocities and the platforms' recent looks (or steps a Vigil
  session) to Vigil, and returns ``[{platform: [action]}]``: per platform the
  move to the first cell of its plan, each checked to be legal.
* :class:`VigilMap`, the mapping between Stone Soup coordinates and Vigil's
  zone and cells, with the legality of moves per sensor type
  (:meth:`VigilMap.check_move`) and the scenario's obstacles
  (:class:`Obstacle`, :meth:`VigilMap.clear`).
* :class:`LatticeActionableMovable`, a
  :class:`~stonesoup.movable.max_speed.MaxSpeedActionableMovable` whose
  action generator yields exactly the legal moves (king moves of at most the
  sensor type's speed through cells free for the type), so that Stone
  Soup's own managers choose from the same moves as Vigil.
* :class:`VigilFOVSensor`, a Stone Soup sensor with Vigil's field of view
  and sight lines, and :func:`make_platform`, a platform of either kind with
  an explicit id.
* :class:`VigilGroundTruthSimulator`, ground truth that follows Vigil's
  target model (Stone Soup has no simulator of targets born at fixed points
  outside the area that fly straight and leave, or end at a building).

Obstacles
---------
A scenario's ``obstacles`` are convex polygons of kind ``building`` or
``screen``. Both block the sight of ground sensor types (a look detects a
target only if the open segment from the sensor's cell centre to the target
meets no obstacle's interior; touching an edge or a vertex does not block);
``elevated`` types (``sensor_types.NAME.elevated``, e.g. a drone) see over
them. A building also ends the flight of a target that enters it, and keeps
ground types off every cell whose centre it holds (edges included), like
``no_go``; elevated types may stand on and cross those cells. Every class
here follows these rules: :meth:`VigilMap.is_free` and the moves take the
sensor type, :class:`VigilFOVSensor` checks sight lines and
:class:`VigilGroundTruthSimulator` stops targets at buildings.

Coordinates and cells
---------------------
Vigil's zone is ``[0, W] x [0, H]`` with x east and y north, in the units of
the scenario (metres, say). Stone Soup coordinates are Vigil's plus
``origin`` (``(0, 0)`` by default): a platform at Stone Soup ``(x, y)`` is
at Vigil ``(x - origin[0], y - origin[1])``. Platforms' positions are their
movable's ``position`` (its first two components are x and y); tracks'
states are ``[x, vx, y, vy]`` by default (Stone Soup's constant-velocity
ordering; see ``track_position_mapping``/``track_velocity_mapping``), with
velocities per second. One Vigil step is one ``time_step`` of Stone Soup
time (1 s by default): Vigil receives velocities as displacements per step.

Cell ``(col, row)`` is the square ``[col*c, (col+1)*c) x [row*c, (row+1)*c)``
of side ``c = cell_size``; a position belongs to the cell that holds it, and
a platform moved by the manager always stands at a cell's centre
``((col + 1/2) c, (row + 1/2) c)`` (plus ``origin``). Start platforms at cell
centres: Vigil plans from the cell that holds the platform, and looks are
modelled from cell centres.

What a Stone Soup sensor must be for Vigil's model to apply
-----------------------------------------------------------
Vigil plans for sensors whose *look* at a step, from the cell centre where
the platform stands, detects every target inside the sensor type's field of
view independently with probability ``p_detect`` and nothing outside it.
The platform's sensor must therefore have (for a ground type with
obstacles, only along clear sight lines, see *Obstacles*):

* for a ``square`` field of view of ``half_width`` h: coverage of the
  axis-aligned closed square ``|dx| <= h and |dy| <= h`` around the
  platform (not rotated with the platform's heading);
* for a ``circle`` of ``radius`` r: coverage of the closed disk
  ``dx^2 + dy^2 <= r^2``, i.e. a range-limited sensor with a 360-degree
  field of view and ``max_range = r`` (a radar's ``max_range`` with
  ``fov_angle = 2*pi``);
* detection probability ``p_detect`` of the type (1 unless the scenario
  says otherwise), independent from target to target and look to look, no
  clutter Vigil would have to tell apart, and one look per step;
* coverage clipped to the zone: targets outside the zone do not exist in
  Vigil's model.

:class:`VigilFOVSensor` is such a sensor (``VigilFOVSensor.for_type``
builds it from the scenario's type). A different coverage still gets plans,
but Vigil's expected detections no longer describe what the sensor sees.
Targets must also move as Vigil's model says (straight, constant speed,
from the scenario's sources) for its estimate of the unseen targets to hold;
:class:`VigilGroundTruthSimulator` generates such targets.
"""

from __future__ import annotations

import datetime
import math
import re
from collections import deque
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

try:
    from stonesoup.base import Property
    from stonesoup.buffered_generator import BufferedGenerator
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.movable.action.move_position_action import (
        MaxSpeedPositionActionGenerator,
        MovePositionAction,
    )
    from stonesoup.movable.max_speed import MaxSpeedActionableMovable
    from stonesoup.platform.base import Platform
    from stonesoup.sensor.sensor import SimpleSensor
    from stonesoup.sensormanager.base import SensorManager
    from stonesoup.simulator.base import GroundTruthSimulator
    from stonesoup.types.array import CovarianceMatrix, StateVector
    from stonesoup.types.detection import TrueDetection
    from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState
    from stonesoup.types.state import State
except ImportError as err:  # pragma: no cover - only without the extra
    raise ImportError(
        "vigil_client.stonesoup needs Stone Soup: pip install 'vigil-client[stonesoup]' "
        "(or pip install './clients/python[stonesoup]' from the repository)"
    ) from err

from . import Vigil

__all__ = [
    "OBSTACLE_KINDS",
    "IllegalMoveError",
    "LatticeActionableMovable",
    "LatticeMoveActionGenerator",
    "Obstacle",
    "SensorType",
    "VigilFOVSensor",
    "VigilGroundTruthSimulator",
    "VigilMap",
    "VigilSensorManager",
    "check_actions",
    "make_platform",
]

Cell = tuple[int, int]
"""A cell ``(col, row)``."""

_HEADING_DEGREES = {"east": 0.0, "north": 90.0, "west": 180.0, "south": 270.0}
_KING = [(dc, dr) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if (dc, dr) != (0, 0)]


class IllegalMoveError(ValueError):
    """A move that a Vigil sensor of its type could not make in one step."""


@dataclass(frozen=True)
class SensorType:
    """One of a scenario's sensor types: field of view, speed, ``p_detect``
    and whether it is ``elevated``.

    ``shape`` is ``"square"`` (``size`` is the half-width) or ``"circle"``
    (``size`` is the radius); ``speed`` is in king moves (cells) per step.
    An elevated type (a drone) sees over every obstacle and may stand on
    and cross building cells; a ground type (``elevated`` false, always so
    for ``default``) does neither.
    """

    name: str
    shape: str
    size: float
    speed: int
    p_detect: float
    elevated: bool = False

    def covers(self, centre: Sequence[float], point: Sequence[float]) -> bool:
        """True when the closed field of view centred at ``centre`` holds
        ``point`` (the field of view only: obstacles are the map's, see
        :meth:`VigilMap.sees`)."""
        return _in_view(self.shape, self.size, centre, point)


def _in_view(shape: str, size: float, centre: Sequence[float], point: Sequence[float]) -> bool:
    """True when the closed square (half-width ``size``) or disk (radius
    ``size``) centred at ``centre`` holds ``point``."""
    dx, dy = float(point[0]) - float(centre[0]), float(point[1]) - float(centre[1])
    if shape == "square":
        return abs(dx) <= size and abs(dy) <= size
    return dx * dx + dy * dy <= size * size


def _fov(fov: Mapping[str, Any]) -> tuple[str, float]:
    shape = fov.get("shape", "square")
    if shape == "square":
        return "square", float(fov["half_width"])
    if shape == "circle":
        return "circle", float(fov["radius"])
    raise ValueError(f"unknown field of view shape {shape!r}")


OBSTACLE_KINDS = ("building", "screen")
"""The obstacle kinds: a ``building`` blocks sight, ends the flight of a
target that enters it and keeps ground sensors off the cells whose centres
it holds; a ``screen`` (trees, a hedge, smoke) blocks sight only."""


class Obstacle:
    """One of a scenario's obstacles: a convex polygon in Vigil's
    coordinates and its ``kind`` (``"building"`` or ``"screen"``).

    ``vertices`` are given in either order around the polygon (as in the
    spec's ``polygon``) and kept counter-clockwise; the polygon must be
    convex, with no repeated vertex and no three consecutive vertices
    collinear (``ValueError`` otherwise). Its interior is the intersection
    of the open half-planes left of its edges.
    """

    __slots__ = ("vertices", "kind", "bbox", "eps", "_edges")

    def __init__(self, vertices: Sequence[Sequence[float]], kind: str = "building"):
        if kind not in OBSTACLE_KINDS:
            raise ValueError(f"unknown obstacle kind {kind!r}: 'building' or 'screen'")
        points = [(float(v[0]), float(v[1])) for v in vertices]
        n = len(points)
        if n < 3:
            raise ValueError(f"a polygon needs at least 3 vertices, got {n}")
        if not all(math.isfinite(c) for v in points for c in v):
            raise ValueError("the vertices must be pairs of finite numbers")
        if len(set(points)) != n:
            raise ValueError("a vertex is repeated")
        scale = max(1.0, max(max(abs(x), abs(y)) for x, y in points))
        sign, turning = 0.0, 0.0
        for i in range(n):
            (ax, ay), (bx, by), (cx, cy) = points[i], points[(i + 1) % n], points[(i + 2) % n]
            ux, uy, vx, vy = bx - ax, by - ay, cx - bx, cy - by
            cross = ux * vy - uy * vx
            if abs(cross) <= 1e-12 * math.hypot(ux, uy) * math.hypot(vx, vy) + 1e-15 * scale * scale:
                raise ValueError(f"vertices {i}, {(i + 1) % n} and {(i + 2) % n} are collinear")
            if sign != 0.0 and math.copysign(1.0, cross) != sign:
                raise ValueError(f"the polygon is not convex (it turns both ways at vertex {(i + 1) % n})")
            sign = math.copysign(1.0, cross)
            turning += math.atan2(cross, ux * vx + uy * vy)
        if round(abs(turning) / math.tau) != 1:
            raise ValueError("the polygon intersects itself")
        if sign < 0:
            points.reverse()
        self.vertices: tuple[tuple[float, float], ...] = tuple(points)
        """The vertices, counter-clockwise."""
        self.kind = kind
        xs, ys = [x for x, _ in points], [y for _, y in points]
        self.bbox = (min(xs), min(ys), max(xs), max(ys))
        """``(x0, y0, x1, y1)``, the bounding box."""
        self.eps = 1e-9 * scale
        """Tolerance of :meth:`contains_closed` (as the server's)."""
        # Edge i from vertex i to i + 1: (a, b - a, |b - a|).
        self._edges = tuple(
            (a[0], a[1], b[0] - a[0], b[1] - a[1], math.hypot(b[0] - a[0], b[1] - a[1]))
            for a, b in zip(points, points[1:] + points[:1], strict=True)
        )

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any]) -> Obstacle:
        """From one of the spec's ``obstacles``: ``{"polygon": [[x, y], ...],
        "kind": "building" | "screen"}`` (``kind`` ``building`` by default)."""
        return cls(spec["polygon"], spec.get("kind") or "building")

    @property
    def is_building(self) -> bool:
        return self.kind == "building"

    def __repr__(self) -> str:
        return f"Obstacle({list(self.vertices)!r}, kind={self.kind!r})"

    def contains_open(self, xy: Sequence[float]) -> bool:
        """True when Vigil ``(x, y)`` lies in the open interior."""
        x, y = float(xy[0]), float(xy[1])
        return all(ex * (y - ay) - ey * (x - ax) > 0.0 for ax, ay, ex, ey, _ in self._edges)

    def contains_closed(self, xy: Sequence[float]) -> bool:
        """True when Vigil ``(x, y)`` lies in the closed polygon, within
        :attr:`eps` of its edges (a point on an edge, up to rounding, is
        inside)."""
        x, y = float(xy[0]), float(xy[1])
        return all(
            ex * (y - ay) - ey * (x - ax) >= -self.eps * length
            for ax, ay, ex, ey, length in self._edges
        )

    def line_interior(self, o: Sequence[float], d: Sequence[float]) -> tuple[float, float] | None:
        """The open parameter interval ``(t0, t1)`` of the line ``o + t d``
        inside the open interior (``t0 < t1``, either may be infinite), or
        None when the line misses it or only touches its boundary.

        Cyrus–Beck: the interior is the intersection of the edges' open
        half-planes, so the line is inside on the intersection of one open
        interval of ``t`` per edge. Exact up to the rounding of one cross
        product per edge (exact for integer coordinates)."""
        ox, oy, dx, dy = float(o[0]), float(o[1]), float(d[0]), float(d[1])
        t0, t1 = -math.inf, math.inf
        for ax, ay, ex, ey, _ in self._edges:
            # Left of the edge: cross(e, o + t d - a) = num + t den > 0.
            num = ex * (oy - ay) - ey * (ox - ax)
            den = ex * dy - ey * dx
            if den > 0.0:
                t0 = max(t0, -num / den)
            elif den < 0.0:
                t1 = min(t1, -num / den)
            elif num <= 0.0:
                return None  # parallel to the edge, on it or outside
            if t0 >= t1:
                return None
        return t0, t1

    def blocks(self, p: Sequence[float], q: Sequence[float]) -> bool:
        """True when the open segment from Vigil ``p`` to ``q`` meets the
        open interior (touching an edge or a vertex does not block; from a
        point inside, every segment is blocked, even to itself)."""
        px, py, qx, qy = float(p[0]), float(p[1]), float(q[0]), float(q[1])
        x0, y0, x1, y1 = self.bbox
        if max(px, qx) <= x0 or min(px, qx) >= x1 or max(py, qy) <= y0 or min(py, qy) >= y1:
            return False  # the closed segment's box meets no interior point
        span = self.line_interior((px, py), (qx - px, qy - py))
        return span is not None and max(span[0], 0.0) < min(span[1], 1.0)

    def stop(self, o: Sequence[float], u: Sequence[float]) -> float:
        """How far along the ray ``o + t u`` (``t >= 0``) it first enters the
        open interior (0 from inside), or infinity; ``t`` in units of
        ``|u|``."""
        span = self.line_interior(o, u)
        if span is None or span[1] <= 0.0:
            return math.inf
        return max(span[0], 0.0)


def _obstacles(spec: Mapping[str, Any]) -> list[Obstacle]:
    out = []
    for i, o in enumerate(spec.get("obstacles") or []):
        try:
            out.append(Obstacle.from_spec(o))
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"obstacles[{i}]: {e}") from None
    return out


class VigilMap:
    """Vigil's zone, lattice and obstacles in Stone Soup coordinates.

    Built from a scenario spec (the JSON of ``GET /v1/scenarios/{id}``'s
    ``spec``). Stone Soup coordinates are Vigil's plus ``origin``. Cells are
    ``(col, row)`` tuples. A cell is free for a sensor type when it is on
    the lattice, its centre is in no ``no_go`` rectangle (edges included)
    and, for a ground type (not ``elevated``; ``default`` never is), its
    centre is in no building (the closed polygon, within a rounding
    tolerance: a centre on an edge is inside). Screens never block cells.
    The cell methods take a ``type_name``, ``"default"`` when left out.

    ``obstacles`` (:class:`Obstacle`, in Vigil's coordinates) block ground
    sensors' sight lines: :meth:`clear` and :meth:`sees`.
    """

    def __init__(self, spec: Mapping[str, Any], origin: Sequence[float] = (0.0, 0.0)):
        self.spec = dict(spec)
        self.width = float(spec["zone"]["width"])
        self.height = float(spec["zone"]["height"])
        self.cell_size = float(spec["cell_size"])
        self.cols = int(round(self.width / self.cell_size))
        self.rows = int(round(self.height / self.cell_size))
        self.origin = (float(origin[0]), float(origin[1]))
        self.no_go = [
            (float(r["x0"]), float(r["y0"]), float(r["x1"]), float(r["y1"]))
            for r in spec.get("no_go") or []
        ]
        self.obstacles: list[Obstacle] = _obstacles(spec)
        """The buildings and screens, in the spec's order (Vigil coordinates)."""
        shape, size = _fov(spec["fov"])
        self.sensor_types = {
            "default": SensorType(
                "default",
                shape,
                size,
                int(spec.get("sensor_speed") or 1),
                float(spec.get("p_detect") or 1.0),
            )
        }
        for name, t in (spec.get("sensor_types") or {}).items():
            shape, size = _fov(t["fov"])
            self.sensor_types[name] = SensorType(
                name, shape, size, int(t.get("speed") or 1), float(t.get("p_detect") or 1.0),
                bool(t.get("elevated") or False),
            )
        self._building_cells = frozenset(self._cells_in_buildings())

    def _cells_in_buildings(self) -> Iterator[Cell]:
        c = self.cell_size
        for o in self.obstacles:
            if not o.is_building:
                continue
            x0, y0, x1, y1 = o.bbox
            # Only the cells whose centres may lie in the bounding box.
            for row in range(max(0, math.floor((y0 - o.eps) / c - 1)),
                             min(self.rows, math.ceil((y1 + o.eps) / c + 1))):
                for col in range(max(0, math.floor((x0 - o.eps) / c - 1)),
                                 min(self.cols, math.ceil((x1 + o.eps) / c + 1))):
                    if o.contains_closed(((col + 0.5) * c, (row + 0.5) * c)):
                        yield col, row

    def sensor_type(self, name: str = "default") -> SensorType:
        """The sensor type ``name``; ``KeyError`` naming the known ones otherwise."""
        try:
            return self.sensor_types[name]
        except KeyError:
            raise KeyError(
                f"the scenario has no sensor type {name!r} (it has {', '.join(self.sensor_types)})"
            ) from None

    def to_vigil(self, xy: Sequence[float]) -> tuple[float, float]:
        """Stone Soup ``(x, y)`` to Vigil's ``(x, y)``."""
        return float(xy[0]) - self.origin[0], float(xy[1]) - self.origin[1]

    def from_vigil(self, xy: Sequence[float]) -> tuple[float, float]:
        """Vigil's ``(x, y)`` to Stone Soup ``(x, y)``."""
        return float(xy[0]) + self.origin[0], float(xy[1]) + self.origin[1]

    def in_zone(self, xy: Sequence[float]) -> bool:
        """True when Stone Soup ``(x, y)`` lies in the closed zone."""
        x, y = self.to_vigil(xy)
        return 0.0 <= x <= self.width and 0.0 <= y <= self.height

    def cell_of(self, xy: Sequence[float]) -> Cell:
        """The cell holding Stone Soup ``(x, y)`` (the zone's far edges belong
        to the last column and row). ``ValueError`` outside the zone."""
        if not self.in_zone(xy):
            x, y = self.to_vigil(xy)
            raise ValueError(
                f"({x:g}, {y:g}) in Vigil's coordinates is outside the zone "
                f"[0,{self.width:g}]x[0,{self.height:g}]"
            )
        x, y = self.to_vigil(xy)
        col = min(int(math.floor(x / self.cell_size)), self.cols - 1)
        row = min(int(math.floor(y / self.cell_size)), self.rows - 1)
        return col, row

    def centre(self, cell: Cell) -> np.ndarray:
        """Stone Soup ``(x, y)`` of a cell's centre."""
        col, row = cell
        return np.array(
            self.from_vigil(((col + 0.5) * self.cell_size, (row + 0.5) * self.cell_size))
        )

    def on_lattice(self, cell: Cell) -> bool:
        return 0 <= cell[0] < self.cols and 0 <= cell[1] < self.rows

    # -- where sensors may stand

    def in_building(self, xy: Sequence[float]) -> bool:
        """True when Stone Soup ``(x, y)`` lies in a building (closed, within
        the rounding tolerance of its edges)."""
        v = self.to_vigil(xy)
        return any(o.is_building and o.contains_closed(v) for o in self.obstacles)

    def blocked_reason(self, cell: Cell, type_name: str = "default") -> str | None:
        """Why a sensor of type ``type_name`` may not stand on ``cell``
        (off the lattice, no-go ground, or a building for a ground type), or
        None when it may."""
        elevated = self.sensor_type(type_name).elevated
        if not self.on_lattice(cell):
            return "off the lattice"
        x, y = (cell[0] + 0.5) * self.cell_size, (cell[1] + 0.5) * self.cell_size
        if any(x0 <= x <= x1 and y0 <= y <= y1 for x0, y0, x1, y1 in self.no_go):
            return "no-go ground"
        if not elevated and cell in self._building_cells:
            return f"a building (no ground sensor, as type {type_name!r} is, may stand there)"
        return None

    def is_free(self, cell: Cell, type_name: str = "default") -> bool:
        """On the lattice, not blocked by a no-go rectangle, and for a ground
        type ``type_name`` its centre in no building."""
        return self.blocked_reason(cell, type_name) is None

    def free_cells(self, type_name: str = "default") -> list[Cell]:
        """Every cell free for ``type_name``, row by row from the south-west."""
        return [
            (c, r)
            for r in range(self.rows)
            for c in range(self.cols)
            if self.is_free((c, r), type_name)
        ]

    def reachable(
        self, cell: Cell, speed: int | None = None, type_name: str = "default"
    ) -> dict[Cell, int]:
        """The cells a sensor of type ``type_name`` and ``speed`` (king moves
        per step; the type's by default) at free ``cell`` can end a step on,
        each with the fewest moves it takes: every cell on the way and at the
        end free for the type. Holds ``cell`` (0 moves)."""
        if speed is None:
            speed = self.sensor_type(type_name).speed
        seen = {cell: 0}
        frontier = [cell]
        for k in range(1, speed + 1):
            nxt = []
            for c, r in frontier:
                for dc, dr in _KING:
                    n = (c + dc, r + dr)
                    if n not in seen and self.is_free(n, type_name):
                        seen[n] = k
                        nxt.append(n)
            frontier = nxt
        return seen

    def check_move(
        self,
        start: Sequence[float],
        end: Sequence[float],
        speed: int | None = None,
        type_name: str = "default",
    ) -> Cell:
        """Checks that a platform of type ``type_name`` at Stone Soup
        ``start`` may move to ``end`` in one step with ``speed`` king moves
        (the type's by default): ``start`` in a cell free for the type,
        ``end`` the centre of such a cell reachable in at most ``speed`` king
        moves through such cells. Returns the end cell; raises
        :class:`IllegalMoveError` saying what is wrong otherwise."""
        if speed is None:
            speed = self.sensor_type(type_name).speed
        try:
            a = self.cell_of(start)
            b = self.cell_of(end)
        except ValueError as e:
            raise IllegalMoveError(f"move {tuple(start)} -> {tuple(end)}: {e}") from None
        why = self.blocked_reason(a, type_name)
        if why is not None:
            raise IllegalMoveError(f"the platform stands on {why}, cell {a}")
        why = self.blocked_reason(b, type_name)
        if why is not None:
            raise IllegalMoveError(f"move to {why}, cell {b}")
        if not np.allclose(self.centre(b), np.asarray(end[:2], dtype=float), atol=1e-6):
            raise IllegalMoveError(f"move to {tuple(end)}, not the centre of cell {b}")
        if b not in self.reachable(a, speed, type_name):
            raise IllegalMoveError(
                f"move from cell {a} to cell {b} takes more than {speed} king move(s) "
                f"through cells free for type {type_name!r}"
            )
        return b

    # -- what sensors see

    def clear(self, p: Sequence[float], q: Sequence[float]) -> bool:
        """True when the open segment from Stone Soup ``p`` to ``q`` meets no
        obstacle's interior (buildings and screens alike; a segment that
        only touches an edge or a vertex is clear)."""
        vp, vq = self.to_vigil(p), self.to_vigil(q)
        return not any(o.blocks(vp, vq) for o in self.obstacles)

    def sees(self, type_name: str, centre: Sequence[float], point: Sequence[float]) -> bool:
        """True when a look of type ``type_name`` from Stone Soup ``centre``
        can detect a target at ``point``: inside its field of view and the
        zone, and (for a ground type) on a clear sight line."""
        t = self.sensor_type(type_name)
        return (
            t.covers(centre, point)
            and self.in_zone(point)
            and (t.elevated or self.clear(centre, point))
        )

    def flight_stop(self, source: Sequence[float], direction: Sequence[float]) -> float:
        """How far a target flying from Vigil ``source`` along ``direction``
        (in units of its length) goes before it first enters a building's
        interior (0 from inside one), or infinity: its flight ends there."""
        return min(
            (o.stop(source, direction) for o in self.obstacles if o.is_building),
            default=math.inf,
        )


def _xy(position) -> np.ndarray:
    """The first two components of a position vector, as floats."""
    return np.asarray(position, dtype=float).ravel()[:2]


# ---------------------------------------------------------------------------
# Movables whose actions are the legal moves


class LatticeMoveActionGenerator(MaxSpeedPositionActionGenerator):
    """The legal moves of a Vigil sensor of type ``type_name``: staying, or
    going to the centre of any cell free for the type within
    ``speed_cells`` king moves through such cells (a ground type never
    stands on or crosses a building's cell; an elevated one may).
    ``__contains__`` and ``action_from_value`` accept exactly those."""

    vigil_map: VigilMap = Property(default=None, doc="The zone and its cells.")
    speed_cells: int = Property(default=1, doc="King moves per step.")
    type_name: str = Property(default="default", doc="The Vigil sensor type that moves.")

    def _cells(self):
        start = self.vigil_map.cell_of(_xy(self.current_value))
        return self.vigil_map.reachable(start, self.speed_cells, self.type_name)

    def _target(self, cell: Cell) -> StateVector:
        value = np.array(self.current_value, dtype=float)
        value[list(self.action_mapping), 0] = self.vigil_map.centre(cell)
        return StateVector(value)

    def __contains__(self, item) -> bool:
        if isinstance(item, MovePositionAction):
            item = item.target_value
        try:
            self.vigil_map.check_move(
                _xy(self.current_value), _xy(item), self.speed_cells, self.type_name
            )
        except IllegalMoveError:
            return False
        return True

    def __iter__(self) -> Iterator[MovePositionAction]:
        """Stay first, then the reachable cells in ring and row order."""
        yield self.default_action
        here = self.vigil_map.cell_of(_xy(self.current_value))
        cells = sorted(self._cells().items(), key=lambda kv: (kv[1], kv[0][1], kv[0][0]))
        for cell, _ in cells:
            if cell == here:
                continue
            yield MovePositionAction(
                generator=self, end_time=self.end_time, target_value=self._target(cell)
            )


class LatticeActionableMovable(MaxSpeedActionableMovable):
    """A :class:`MaxSpeedActionableMovable` whose actions are a Vigil sensor's
    legal moves (see :class:`LatticeMoveActionGenerator`). Give it
    ``vigil_map``, ``speed_cells`` (the sensor type's speed) and
    ``type_name`` (the sensor type: whether it may cross buildings)."""

    generator = LatticeMoveActionGenerator
    _generator_kwargs = MaxSpeedActionableMovable._generator_kwargs | {
        "vigil_map",
        "speed_cells",
        "type_name",
    }

    vigil_map: VigilMap = Property(default=None, doc="The zone and its cells.")
    speed_cells: int = Property(default=1, doc="King moves per step.")
    type_name: str = Property(default="default", doc="The Vigil sensor type that moves.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if self.vigil_map is None:
            raise ValueError("LatticeActionableMovable needs a vigil_map")
        self.vigil_map.sensor_type(self.type_name)  # KeyError for an unknown type


# ---------------------------------------------------------------------------
# A sensor with Vigil's field of view


class VigilFOVSensor(SimpleSensor):
    """A position sensor with a Vigil field of view: it detects each target
    inside its closed square (``|dx|, |dy| <= half_width``, axis-aligned) or
    disk (``radius``) around the platform, and inside the zone when
    ``vigil_map`` is given, with probability ``p_detect``, independently;
    nothing outside. Measurements are ``(x, y)`` with Gaussian noise of
    ``noise_covar`` (``mapping`` picks x and y from the target state).
    Detection draws use ``seed`` (or numpy's global state).

    With a ``vigil_map`` whose scenario has obstacles, a ground sensor
    (``elevated`` false) detects a target only along a clear sight line:
    the open segment from the platform to the target meets no obstacle's
    interior (buildings and screens; a line that only touches an edge or a
    vertex is clear, and a sensor inside a screen sees nothing). An
    ``elevated`` sensor sees over every obstacle."""

    shape: str = Property(default="square", doc="'square' or 'circle'.")
    size: float = Property(default=1.0, doc="Half-width of a square, radius of a circle.")
    p_detect: float = Property(default=1.0, doc="Probability of detecting a target in view.")
    ndim_state: int = Property(default=4, doc="Dimensions of the target state.")
    mapping: tuple = Property(default=(0, 2), doc="Target state indices of x and y.")
    noise_covar: CovarianceMatrix = Property(
        default=None, doc="Measurement noise covariance (2x2); identity by default."
    )
    vigil_map: VigilMap = Property(
        default=None,
        doc="Clips the view to the zone, and its obstacles block sight lines, when given.",
    )
    elevated: bool = Property(default=False, doc="Sees over every obstacle (a drone).")

    @classmethod
    def for_type(cls, vigil_map: VigilMap, type_name: str = "default", **kwargs):
        """The sensor of the scenario's type ``type_name``, clipped to the
        zone, its sight blocked by the obstacles unless the type is elevated."""
        t = vigil_map.sensor_type(type_name)
        return cls(
            shape=t.shape, size=t.size, p_detect=t.p_detect, vigil_map=vigil_map,
            elevated=t.elevated, **kwargs
        )

    @property
    def measurement_model(self):
        covar = self.noise_covar if self.noise_covar is not None else np.eye(2)
        return LinearGaussian(
            ndim_state=self.ndim_state, mapping=self.mapping, noise_covar=CovarianceMatrix(covar)
        )

    def covers_at(self, centre: Sequence[float], point: Sequence[float]) -> bool:
        """True when the sensor standing at Stone Soup ``centre`` has ``point``
        (Stone Soup ``(x, y)``) in view: in its field of view, in the zone
        and on a clear sight line (see the class)."""
        if not _in_view(self.shape, self.size, centre, point):
            return False
        if self.vigil_map is None:
            return True
        return self.vigil_map.in_zone(point) and (
            self.elevated or self.vigil_map.clear(centre, point)
        )

    def is_detectable(self, state, measurement_model=None) -> bool:
        """In view (before the ``p_detect`` draw of :meth:`measure`)."""
        sv = np.asarray(state.state_vector, dtype=float).ravel()
        return self.covers_at(_xy(self.position), sv[list(self.mapping)])

    def is_clutter_detectable(self, state) -> bool:
        return True

    def measure(self, ground_truths, noise=True, random_state=None, **kwargs):
        """Detects each target in view with probability ``p_detect``. The
        draws are made in the order of the targets' positions, so a seeded
        sensor gives the same detections for the same truths."""
        rng = random_state if random_state is not None else self.random_state
        if rng is None:
            rng = np.random.mtrand._rand
        model = self.measurement_model
        in_view = sorted(
            (t for t in ground_truths if self.is_detectable(t)),
            key=lambda t: tuple(np.asarray(t.state_vector, dtype=float).ravel()),
        )
        detections = set()
        for truth in in_view:
            if self.p_detect < 1.0 and rng.random_sample() >= self.p_detect:
                continue
            z = model.function(truth, noise=False)
            if noise is True:
                z = z + model.rvs(random_state=rng)
            detections.add(
                TrueDetection(
                    z, measurement_model=model, timestamp=truth.timestamp, groundtruth_path=truth
                )
            )
        return detections


def make_platform(
    platform_id: str,
    position: Sequence[float],
    timestamp: datetime.datetime,
    vigil_map: VigilMap,
    type_name: str = "default",
    *,
    time_step: datetime.timedelta = datetime.timedelta(seconds=1),
    sensor_kwargs: Mapping[str, Any] | None = None,
) -> Platform:
    """A platform with id ``platform_id`` at Stone Soup ``position`` (snapped
    to its cell's centre, which must be free for the type: ``ValueError``
    otherwise), with a :class:`LatticeActionableMovable` of the type's speed
    and one :class:`VigilFOVSensor` of the type. Its ``max_speed`` covers the
    longest legal move (``speed`` diagonal cells in ``time_step``), so
    ``action_from_value`` accepts every legal move."""
    t = vigil_map.sensor_type(type_name)
    cell = vigil_map.cell_of(position)
    why = vigil_map.blocked_reason(cell, type_name)
    if why is not None:
        raise ValueError(f"platform {platform_id!r} would stand on {why}, cell {cell}")
    centre = vigil_map.centre(cell)
    max_speed = t.speed * vigil_map.cell_size * math.sqrt(2.0) / time_step.total_seconds()
    movable = LatticeActionableMovable(
        states=[State(StateVector(centre), timestamp=timestamp)],
        position_mapping=(0, 1),
        vigil_map=vigil_map,
        speed_cells=t.speed,
        type_name=type_name,
        max_speed=max_speed * (1 + 1e-9),
    )
    sensor = VigilFOVSensor.for_type(vigil_map, type_name, **dict(sensor_kwargs or {}))
    return Platform(movement_controller=movable, sensors=[sensor], id=str(platform_id))


def _movable_type(platform) -> str | None:
    """The Vigil type a platform's movable moves as (a
    :class:`LatticeActionableMovable`'s ``type_name``), or None."""
    movable = getattr(platform, "movement_controller", None)
    return movable.type_name if isinstance(movable, LatticeActionableMovable) else None


def check_actions(
    config: Mapping[Any, Sequence[Any]],
    vigil_map: VigilMap,
    speeds: Mapping[str, int] | int | None = 1,
    types: Mapping[str, str] | str | None = None,
) -> None:
    """Checks a ``{platform: [action]}`` configuration: each platform's first
    move action must be legal for its sensor type and speed. ``types`` is a
    ``{platform id: type}`` mapping or one type for all; by default each
    platform's :class:`LatticeActionableMovable` ``type_name``, else
    ``default``. ``speeds`` is a ``{platform id: speed}`` mapping, one speed
    for all, or None for each type's speed. Raises
    :class:`IllegalMoveError`."""
    for platform, actions in config.items():
        moves = [a for a in actions if isinstance(a, MovePositionAction)]
        if not moves:
            continue
        pid = getattr(platform, "id", None)
        if types is None:
            type_name = _movable_type(platform) or "default"
        else:
            type_name = types if isinstance(types, str) else types.get(pid, "default")
        if speeds is None:
            speed = vigil_map.sensor_type(type_name).speed
        else:
            speed = speeds if isinstance(speeds, int) else speeds[pid]
        try:
            vigil_map.check_move(
                _xy(platform.position), _xy(moves[0].target_value), speed, type_name
            )
        except IllegalMoveError as e:
            raise IllegalMoveError(f"platform {pid!r}: {e}") from None


# ---------------------------------------------------------------------------
# The manager

_UUID = re.compile(r"^[0-9a-f]{8}-[0-9a-f]{4}-4[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}$")


class VigilSensorManager(SensorManager):
    """A Stone Soup sensor manager that asks Vigil where the platforms go.

    ``platforms`` are the actionable platforms: each needs an explicit,
    unique ``id`` (Vigil's sensor id; Stone Soup's default is a random
    UUID, which is refused) and a movable whose ``actions()`` yields a
    position generator with ``action_from_value`` (a
    :class:`MaxSpeedActionableMovable`, e.g. :class:`LatticeActionableMovable`
    from :func:`make_platform`). ``sensor_types`` maps platform ids to Vigil
    sensor types (``default`` otherwise); a platform whose
    :class:`LatticeActionableMovable` moves as another type is refused, and
    each move is checked against the platform's type (a ground type never
    stands on or crosses a building's cell).

    Each call of :meth:`choose_actions` is one Vigil step: the platforms
    stand where their last look was taken, and the returned moves end at
    ``timestamp``, one ``time_step`` later. The manager keeps the last
    ``history_steps`` looks itself and sends them with a stateless plan; with
    ``use_session=True`` it steps a Vigil session instead, which keeps the
    looks and the tracks on the server. :meth:`close` deletes that session
    (and closes a client the manager made from a URL).
    """

    vigil: Any = Property(doc="A vigil_client.Vigil, or the base URL of a vigil-server.")
    scenario_id: str = Property(doc="The Vigil scenario the platforms guard.")
    sensor_types: Mapping[str, str] = Property(
        default=None, doc="Vigil sensor type per platform id; 'default' for the others."
    )
    origin: tuple = Property(
        default=(0.0, 0.0), doc="Stone Soup coordinates of Vigil's (0, 0)."
    )
    time_step: datetime.timedelta = Property(
        default=datetime.timedelta(seconds=1), doc="Stone Soup time of one Vigil step."
    )
    history_steps: int = Property(default=16, doc="Steps of looks (and track age) kept, 0..128.")
    plan_options: Mapping[str, Any] = Property(
        default=None,
        doc="Extra plan request fields: horizon, estimator, objective, coordination, "
        "min_separation, gap_target, budget_ms.",
    )
    use_session: bool = Property(default=False, doc="Step a Vigil session instead of planning.")
    learn_rates: bool = Property(
        default=False,
        doc="With use_session: the session learns the sources' rates from the tracks "
        "updated each step (each track id counts once) and plans with them; "
        "``last_response.rates`` has them. A tracker's noise needs ``learn_tolerance``.",
    )
    learn_tolerance: Mapping[str, float] = Property(
        default=None,
        doc="With learn_rates: the session's ``tolerance`` (``traceback``, ``speed``, "
        "``look``; see Vigil's docs/learning.md). Exact data by default.",
    )
    track_position_mapping: tuple = Property(default=(0, 2), doc="x, y in track states.")
    track_velocity_mapping: tuple = Property(default=(1, 3), doc="vx, vy in track states.")

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("take_sensors_from_platforms", False)
        super().__init__(*args, **kwargs)
        self._owns_client = isinstance(self.vigil, str)
        self.client = Vigil(self.vigil) if self._owns_client else self.vigil
        summary = self.client.get_scenario(self.scenario_id)
        spec = summary.spec.to_dict() if hasattr(summary.spec, "to_dict") else dict(summary.spec)
        self.map = VigilMap(spec, self.origin)
        if self.map.obstacles and (self.plan_options or {}).get("estimator") == "paper":
            raise ValueError(
                f"scenario {self.scenario_id!r} has obstacles, which the paper estimator "
                "does not model: choose another estimator in plan_options"
            )
        for pid, name in (self.sensor_types or {}).items():
            try:
                self.map.sensor_type(name)
            except KeyError as e:
                raise ValueError(f"sensor_types[{pid!r}]: {e.args[0]}") from None
        if not 0 <= self.history_steps <= 128:
            raise ValueError(f"history_steps must be in 0..=128, got {self.history_steps}")
        if self.learn_rates and not self.use_session:
            raise ValueError("learn_rates needs use_session=True: a session keeps what it learns")
        self._looks: deque[tuple[datetime.datetime, list[dict]]] = deque()
        self._session = None
        self.last_response = None
        """The last plan or step response (a PlanResponse or StepResponse)."""

    # -- the parts of a request

    def type_of(self, platform) -> str:
        """The Vigil sensor type of ``platform``."""
        return (self.sensor_types or {}).get(platform.id, "default")

    def _platforms(self) -> list:
        platforms = sorted(self.platforms, key=lambda p: str(p.id))
        ids = [str(p.id) for p in platforms]
        if not platforms:
            raise ValueError("the manager has no platforms")
        if len(set(ids)) != len(ids):
            raise ValueError(f"platform ids must be unique, got {ids}")
        for pid in ids:
            if _UUID.match(pid):
                raise ValueError(
                    f"platform id {pid!r} looks like Stone Soup's random default: give every "
                    "platform an explicit id (Platform(..., id='p1')) so that it maps to the "
                    "same Vigil sensor at every step"
                )
        for platform in platforms:
            moves_as = _movable_type(platform)
            if moves_as is not None and moves_as != self.type_of(platform):
                raise ValueError(
                    f"platform {platform.id!r} moves as Vigil type {moves_as!r} (its "
                    f"LatticeActionableMovable) but the manager plans it as "
                    f"{self.type_of(platform)!r}: give sensor_types={{{str(platform.id)!r}: "
                    f"{moves_as!r}}}"
                )
        return platforms

    def _now(self, platforms, timestamp: datetime.datetime) -> datetime.datetime:
        stamps = {p.states[-1].timestamp for p in platforms}
        if len(stamps) != 1:
            raise ValueError(f"the platforms are at different times: {sorted(stamps)}")
        now = stamps.pop()
        if abs((timestamp - now) - self.time_step) > datetime.timedelta(milliseconds=1):
            raise ValueError(
                f"choose_actions plans one Vigil step: timestamp {timestamp} must be "
                f"time_step={self.time_step} after the platforms' time {now}"
            )
        return now

    def _sensor(self, platform) -> dict:
        xy = _xy(platform.position)
        cell = self.map.cell_of(xy)  # ValueError outside the zone
        type_name = self.type_of(platform)
        why = self.map.blocked_reason(cell, type_name)
        if why is not None:
            raise ValueError(f"platform {platform.id!r} stands on {why}, cell {cell}")
        x, y = self.map.to_vigil(xy)
        return {"id": str(platform.id), "x": x, "y": y, "type": type_name}

    def targets(self, tracks, now: datetime.datetime, *, updated_now: bool = False) -> list[dict]:
        """Vigil targets from Stone Soup ``tracks`` at ``now``: each track's
        last state moved at its velocity to ``now``, in Vigil coordinates,
        velocity per step. Tracks last updated more than ``history_steps``
        steps ago, or in the future, or predicted outside the zone, are left
        out (with ``updated_now``, every track not updated at ``now``)."""
        dt = self.time_step.total_seconds()
        out = []
        for track in sorted(tracks, key=lambda t: str(t.id)):
            state = track.state
            age = (now - state.timestamp).total_seconds()
            if age < -1e-6 or age > self.history_steps * dt + 1e-6:
                continue
            if updated_now and abs(age) > 1e-6:
                continue
            sv = np.asarray(state.state_vector, dtype=float).ravel()
            pos = sv[list(self.track_position_mapping)]
            vel = sv[list(self.track_velocity_mapping)]
            pos = pos + vel * age
            if not self.map.in_zone(pos):
                continue
            x, y = self.map.to_vigil(pos)
            out.append({"id": str(track.id), "x": x, "y": y,
                        "vx": float(vel[0] * dt), "vy": float(vel[1] * dt)})
        return out

    def _history(self, now: datetime.datetime) -> list[list[dict]]:
        by_time = dict(self._looks)
        history = []
        for k in range(1, self.history_steps + 1):
            history.append(by_time.get(now - k * self.time_step, []))
        while history and not history[-1]:
            history.pop()
        return history

    def _remember(self, now: datetime.datetime, sensors: list[dict]) -> None:
        look = [{"x": s["x"], "y": s["y"], "type": s["type"]} for s in sensors]
        self._looks = deque((t, v) for t, v in self._looks if t != now)
        self._looks.append((now, look))
        oldest = now - self.history_steps * self.time_step
        while self._looks and self._looks[0][0] < oldest:
            self._looks.popleft()

    def plan_request(self, tracks, timestamp: datetime.datetime) -> dict:
        """The stateless plan request :meth:`choose_actions` would send now
        (without recording the platforms' looks)."""
        platforms = self._platforms()
        now = self._now(platforms, timestamp)
        return self._stateless_request([self._sensor(p) for p in platforms], tracks, now)

    def _stateless_request(self, sensors: list[dict], tracks, now: datetime.datetime) -> dict:
        request = dict(self.plan_options or {})
        request["sensors"] = sensors
        request["targets"] = self.targets(tracks, now)
        history = self._history(now)
        if history:
            request["history"] = history
        return request

    # -- choosing

    def choose_actions(self, tracks, timestamp, nchoose=1, **kwargs):
        """Plans one step with Vigil and returns ``[{platform: [action]}]``.

        ``tracks`` are the tracks now (states ``[x, vx, y, vy]`` by default,
        velocities per second); ``timestamp`` is when the moves end, one
        ``time_step`` after the platforms' current time. Every returned move
        takes its platform to the centre of the first cell of its plan, and
        is checked to be a legal move of its sensor type (else
        :class:`IllegalMoveError`). Vigil returns one plan, so ``nchoose``
        must be 1. Errors of the server raise ``vigil_client.VigilError``.
        """
        if nchoose != 1:
            raise ValueError("VigilSensorManager returns one plan: nchoose must be 1")
        platforms = self._platforms()
        now = self._now(platforms, timestamp)
        sensors = [self._sensor(p) for p in platforms]
        if self.use_session:
            if self._session is None:
                settings = {k: v for k, v in (self.plan_options or {}).items()
                            if k in ("horizon", "estimator", "objective", "coordination",
                                     "min_separation", "observed")}
                if self.learn_rates:
                    settings["learn_rates"] = True
                    if self.learn_tolerance:
                        settings["tolerance"] = dict(self.learn_tolerance)
                self._session = self.client.session(
                    scenario_id=self.scenario_id, history_steps=self.history_steps, **settings
                )
            body = {k: v for k, v in (self.plan_options or {}).items()
                    if k in ("horizon", "estimator", "objective", "coordination",
                             "min_separation", "gap_target", "budget_ms")}
            body["sensors"] = sensors
            body["detections"] = self.targets(tracks, now, updated_now=True)
            response = self._session.step(body)
        else:
            request = self._stateless_request(sensors, tracks, now)
            response = self.client.plan(self.scenario_id, request)
        self._remember(now, sensors)
        self.last_response = response
        return [self._actions(platforms, response, timestamp)]

    def _actions(self, platforms, response, timestamp) -> dict:
        plans = {str(p.sensor): p for p in response.plans}
        config = {}
        for platform in platforms:
            plan = plans.get(str(platform.id))
            if plan is None or not plan.path:
                raise IllegalMoveError(f"Vigil returned no path for platform {platform.id!r}")
            cell = (int(plan.path[0].col), int(plan.path[0].row))
            type_name = self.type_of(platform)
            speed = self.map.sensor_type(type_name).speed
            here = _xy(platform.position)
            target_xy = self.map.centre(cell)
            try:
                self.map.check_move(here, target_xy, speed, type_name)
            except IllegalMoveError as e:
                raise IllegalMoveError(f"platform {platform.id!r}: {e}") from None
            config[platform] = [self._move(platform, target_xy, timestamp)]
        return config

    def _move(self, platform, target_xy, timestamp):
        generators = [g for g in platform.actions(timestamp)
                      if getattr(g, "attribute", None) == "position"
                      and hasattr(g, "action_from_value")]
        if not generators:
            raise TypeError(
                f"platform {platform.id!r} has no position action generator with "
                "action_from_value: give it a MaxSpeedActionableMovable "
                "(or LatticeActionableMovable, see make_platform)"
            )
        gen = generators[0]
        value = np.array(platform.position, dtype=float).reshape(-1, 1)
        value[list(gen.action_mapping), 0] = target_xy
        action = gen.action_from_value(StateVector(value))
        if action is None:
            raise IllegalMoveError(
                f"platform {platform.id!r}: its movable cannot reach {tuple(target_xy)} by "
                f"{timestamp} (a MaxSpeedActionableMovable needs max_speed >= speed * "
                f"cell_size * sqrt(2) / time_step)"
            )
        return action

    def close(self) -> None:
        """Deletes the session (if any) and closes a client made from a URL."""
        if self._session is not None:
            try:
                self._session.delete()
            finally:
                self._session = None
        if self._owns_client:
            self.client.close()


# ---------------------------------------------------------------------------
# Ground truth that follows Vigil's model


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
