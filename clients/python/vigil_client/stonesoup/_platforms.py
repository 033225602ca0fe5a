"""Platforms and their sensor: what moves and what looks.

:class:`LatticeMoveActionGenerator` and :class:`LatticeActionableMovable`
(movables whose actions are exactly a sensor type's legal moves),
:class:`VigilFOVSensor` (Vigil's field of view and sight lines),
:func:`make_platform`, which puts the two on a platform, and
:func:`check_actions`, which checks a ``{platform: [action]}`` configuration.
"""

from __future__ import annotations

import datetime
import math
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np
from stonesoup.base import Property
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.movable.action.move_position_action import (
    MaxSpeedPositionActionGenerator,
    MovePositionAction,
)
from stonesoup.movable.max_speed import MaxSpeedActionableMovable
from stonesoup.platform.base import Platform
from stonesoup.sensor.sensor import SimpleSensor
from stonesoup.types.array import CovarianceMatrix, StateVector
from stonesoup.types.detection import TrueDetection
from stonesoup.types.state import State

from ._map import Cell, IllegalMoveError, VigilMap, _in_view


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
