"""The sensor manager: :class:`VigilSensorManager`, which asks Vigil (a plan,
or a step of a session) where the platforms go and returns their moves.
"""

from __future__ import annotations

import datetime
import re
from collections import deque
from collections.abc import Mapping
from typing import Any

import numpy as np
from stonesoup.base import Property
from stonesoup.sensormanager.base import SensorManager
from stonesoup.types.array import StateVector

from .. import Vigil
from ._map import IllegalMoveError, VigilMap
from ._platforms import _movable_type, _xy

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
