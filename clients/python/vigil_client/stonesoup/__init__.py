"""Vigil as a Stone Soup sensor manager (the ``stonesoup`` extra).

Install with ``pip install './clients/python[stonesoup]'`` (Stone Soup 1.9.1
or later 1.x). This package is imported only by users of the extra; the rest
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

try:
    import stonesoup  # noqa: F401
except ImportError as err:  # pragma: no cover - only without the extra
    raise ImportError(
        "vigil_client.stonesoup needs Stone Soup: pip install 'vigil-client[stonesoup]' "
        "(or pip install './clients/python[stonesoup]' from the repository)"
    ) from err

from ._groundtruth import VigilGroundTruthSimulator
from ._manager import VigilSensorManager
from ._map import OBSTACLE_KINDS, IllegalMoveError, Obstacle, SensorType, VigilMap
from ._map import Cell as Cell
from ._platforms import (
    LatticeActionableMovable,
    LatticeMoveActionGenerator,
    VigilFOVSensor,
    check_actions,
    make_platform,
)

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

# The public classes keep the package as their module, as before it was
# split: Stone Soup's YAML tags, reprs and pickles name them from it.
for _public in (
    IllegalMoveError,
    LatticeActionableMovable,
    LatticeMoveActionGenerator,
    Obstacle,
    SensorType,
    VigilFOVSensor,
    VigilGroundTruthSimulator,
    VigilMap,
    VigilSensorManager,
):
    _public.__module__ = __name__
del _public
