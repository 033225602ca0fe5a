"""The map: Vigil's zone, lattice and obstacles in Stone Soup coordinates.

:class:`VigilMap` (cells, where each sensor type may stand and move, what it
sees), the scenario's :class:`SensorType` and :class:`Obstacle` (convex
polygons, ``OBSTACLE_KINDS``), and :class:`IllegalMoveError`, which
:meth:`VigilMap.check_move` raises. Plain geometry on numpy: nothing here
imports Stone Soup.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

Cell = tuple[int, int]
"""A cell ``(col, row)``."""

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
