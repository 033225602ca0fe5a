from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
    from ..models.fov_spec_type_0 import FovSpecType0
    from ..models.fov_spec_type_1 import FovSpecType1
    from ..models.no_go_spec import NoGoSpec
    from ..models.obstacle_spec import ObstacleSpec
    from ..models.scenario_spec_sensor_types_type_0 import ScenarioSpecSensorTypesType0
    from ..models.source_spec import SourceSpec
    from ..models.zone_spec import ZoneSpec


T = TypeVar("T", bound="ScenarioSpec")


@_attrs_define
class ScenarioSpec:
    """A scenario as clients send it.

    Attributes:
        cell_size (float): Side of a lattice cell; must divide width and height.
        fov (FovSpecType0 | FovSpecType1): Field of view of every sensor, tagged by `shape`.
        sources (list[SourceSpec]): Target sources (at least one).
        zone (ZoneSpec): The surveillance zone `[0,width] × [0,height]`.
        horizon (int | None | Unset): Default planning horizon T (1..=12, default 3).
        min_separation (int | None | Unset): Minimum separation between sensors, cells (0..=16, default 0: no
            rule): at every step of a plan any two sensors stand at Chebyshev
            distance ≥ this many cells wherever that can be kept (1: never on
            one cell). A plan request may override it.
        name (None | str | Unset): Free-form label.
        no_go (list[NoGoSpec] | None | Unset): Ground no sensor may stand on: a cell whose centre lies in one of
            these rectangles (edges included) is blocked. Targets fly over it.
        obstacles (list[ObstacleSpec] | None | Unset): Buildings and screens (at most 64 convex polygons): sight lines
            that meet an obstacle's interior are blocked (elevated sensor types
            see over them), a target's flight ends where it enters a building,
            and no ground sensor stands on or crosses a cell whose centre lies
            in a building (see `docs/obstacles.md`).
        p_detect (float | None | Unset): Detection probability of the type `default`, in (0, 1] (default 1).
        rays_per_pi (int | None | Unset): Rays per π radians in each source's angular grid, over which the
            exact estimator integrates (32..=1024; default 128 when every field
            of view is a square, 384 otherwise). A plan's cost is about linear
            in it, and the error against the model falls about as its square:
            the measured figures are in `docs/performance.md` (*Accuracy*).
        sensor_speed (int | None | Unset): Speed of the type `default`, cells (king moves) per step (1..=3,
            default 1).
        sensor_types (None | ScenarioSpecSensorTypesType0 | Unset): More sensor types, by name (at most 8; names of 1–32
            characters of
            `[A-Za-z0-9_-]`, not `default`).
        target_speed (float | None | Unset): Distance a target flies per step, for the sources that give no
            `speeds` (required unless every source gives them).
    """

    cell_size: float
    fov: FovSpecType0 | FovSpecType1
    sources: list[SourceSpec]
    zone: ZoneSpec
    horizon: int | None | Unset = UNSET
    min_separation: int | None | Unset = UNSET
    name: None | str | Unset = UNSET
    no_go: list[NoGoSpec] | None | Unset = UNSET
    obstacles: list[ObstacleSpec] | None | Unset = UNSET
    p_detect: float | None | Unset = UNSET
    rays_per_pi: int | None | Unset = UNSET
    sensor_speed: int | None | Unset = UNSET
    sensor_types: None | ScenarioSpecSensorTypesType0 | Unset = UNSET
    target_speed: float | None | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        from ..models.fov_spec_type_0 import FovSpecType0  # noqa: PLC0415
        from ..models.scenario_spec_sensor_types_type_0 import (
            ScenarioSpecSensorTypesType0,
        )  # noqa: PLC0415

        cell_size = self.cell_size

        fov: dict[str, Any]
        if isinstance(self.fov, FovSpecType0):
            fov = self.fov.to_dict()
        else:
            fov = self.fov.to_dict()

        sources = []
        for sources_item_data in self.sources:
            sources_item = sources_item_data.to_dict()
            sources.append(sources_item)

        zone = self.zone.to_dict()

        horizon: int | None | Unset
        if isinstance(self.horizon, Unset):
            horizon = UNSET
        else:
            horizon = self.horizon

        min_separation: int | None | Unset
        if isinstance(self.min_separation, Unset):
            min_separation = UNSET
        else:
            min_separation = self.min_separation

        name: None | str | Unset
        if isinstance(self.name, Unset):
            name = UNSET
        else:
            name = self.name

        no_go: list[dict[str, Any]] | None | Unset
        if isinstance(self.no_go, Unset):
            no_go = UNSET
        elif isinstance(self.no_go, list):
            no_go = []
            for no_go_type_0_item_data in self.no_go:
                no_go_type_0_item = no_go_type_0_item_data.to_dict()
                no_go.append(no_go_type_0_item)

        else:
            no_go = self.no_go

        obstacles: list[dict[str, Any]] | None | Unset
        if isinstance(self.obstacles, Unset):
            obstacles = UNSET
        elif isinstance(self.obstacles, list):
            obstacles = []
            for obstacles_type_0_item_data in self.obstacles:
                obstacles_type_0_item = obstacles_type_0_item_data.to_dict()
                obstacles.append(obstacles_type_0_item)

        else:
            obstacles = self.obstacles

        p_detect: float | None | Unset
        if isinstance(self.p_detect, Unset):
            p_detect = UNSET
        else:
            p_detect = self.p_detect

        rays_per_pi: int | None | Unset
        if isinstance(self.rays_per_pi, Unset):
            rays_per_pi = UNSET
        else:
            rays_per_pi = self.rays_per_pi

        sensor_speed: int | None | Unset
        if isinstance(self.sensor_speed, Unset):
            sensor_speed = UNSET
        else:
            sensor_speed = self.sensor_speed

        sensor_types: dict[str, Any] | None | Unset
        if isinstance(self.sensor_types, Unset):
            sensor_types = UNSET
        elif isinstance(self.sensor_types, ScenarioSpecSensorTypesType0):
            sensor_types = self.sensor_types.to_dict()
        else:
            sensor_types = self.sensor_types

        target_speed: float | None | Unset
        if isinstance(self.target_speed, Unset):
            target_speed = UNSET
        else:
            target_speed = self.target_speed

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "cell_size": cell_size,
                "fov": fov,
                "sources": sources,
                "zone": zone,
            }
        )
        if horizon is not UNSET:
            field_dict["horizon"] = horizon
        if min_separation is not UNSET:
            field_dict["min_separation"] = min_separation
        if name is not UNSET:
            field_dict["name"] = name
        if no_go is not UNSET:
            field_dict["no_go"] = no_go
        if obstacles is not UNSET:
            field_dict["obstacles"] = obstacles
        if p_detect is not UNSET:
            field_dict["p_detect"] = p_detect
        if rays_per_pi is not UNSET:
            field_dict["rays_per_pi"] = rays_per_pi
        if sensor_speed is not UNSET:
            field_dict["sensor_speed"] = sensor_speed
        if sensor_types is not UNSET:
            field_dict["sensor_types"] = sensor_types
        if target_speed is not UNSET:
            field_dict["target_speed"] = target_speed

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.fov_spec_type_0 import FovSpecType0  # noqa: PLC0415
        from ..models.fov_spec_type_1 import FovSpecType1  # noqa: PLC0415
        from ..models.no_go_spec import NoGoSpec  # noqa: PLC0415
        from ..models.obstacle_spec import ObstacleSpec  # noqa: PLC0415
        from ..models.scenario_spec_sensor_types_type_0 import (
            ScenarioSpecSensorTypesType0,
        )  # noqa: PLC0415
        from ..models.source_spec import SourceSpec  # noqa: PLC0415
        from ..models.zone_spec import ZoneSpec  # noqa: PLC0415

        d = dict(src_dict)
        cell_size = d.pop("cell_size")

        def _parse_fov(data: object) -> FovSpecType0 | FovSpecType1:
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                componentsschemas_fov_spec_type_0 = FovSpecType0.from_dict(data)

                return componentsschemas_fov_spec_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            if not isinstance(data, dict):
                raise TypeError()
            componentsschemas_fov_spec_type_1 = FovSpecType1.from_dict(data)

            return componentsschemas_fov_spec_type_1

        fov = _parse_fov(d.pop("fov"))

        sources = []
        _sources = d.pop("sources")
        for sources_item_data in _sources:
            sources_item = SourceSpec.from_dict(sources_item_data)

            sources.append(sources_item)

        zone = ZoneSpec.from_dict(d.pop("zone"))

        def _parse_horizon(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        horizon = _parse_horizon(d.pop("horizon", UNSET))

        def _parse_min_separation(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        min_separation = _parse_min_separation(d.pop("min_separation", UNSET))

        def _parse_name(data: object) -> None | str | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(None | str | Unset, data)

        name = _parse_name(d.pop("name", UNSET))

        def _parse_no_go(data: object) -> list[NoGoSpec] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                no_go_type_0 = []
                _no_go_type_0 = data
                for no_go_type_0_item_data in _no_go_type_0:
                    no_go_type_0_item = NoGoSpec.from_dict(no_go_type_0_item_data)

                    no_go_type_0.append(no_go_type_0_item)

                return no_go_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[NoGoSpec] | None | Unset, data)

        no_go = _parse_no_go(d.pop("no_go", UNSET))

        def _parse_obstacles(data: object) -> list[ObstacleSpec] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                obstacles_type_0 = []
                _obstacles_type_0 = data
                for obstacles_type_0_item_data in _obstacles_type_0:
                    obstacles_type_0_item = ObstacleSpec.from_dict(
                        obstacles_type_0_item_data
                    )

                    obstacles_type_0.append(obstacles_type_0_item)

                return obstacles_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[ObstacleSpec] | None | Unset, data)

        obstacles = _parse_obstacles(d.pop("obstacles", UNSET))

        def _parse_p_detect(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        p_detect = _parse_p_detect(d.pop("p_detect", UNSET))

        def _parse_rays_per_pi(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        rays_per_pi = _parse_rays_per_pi(d.pop("rays_per_pi", UNSET))

        def _parse_sensor_speed(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        sensor_speed = _parse_sensor_speed(d.pop("sensor_speed", UNSET))

        def _parse_sensor_types(
            data: object,
        ) -> None | ScenarioSpecSensorTypesType0 | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                sensor_types_type_0 = ScenarioSpecSensorTypesType0.from_dict(data)

                return sensor_types_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | ScenarioSpecSensorTypesType0 | Unset, data)

        sensor_types = _parse_sensor_types(d.pop("sensor_types", UNSET))

        def _parse_target_speed(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        target_speed = _parse_target_speed(d.pop("target_speed", UNSET))

        scenario_spec = cls(
            cell_size=cell_size,
            fov=fov,
            sources=sources,
            zone=zone,
            horizon=horizon,
            min_separation=min_separation,
            name=name,
            no_go=no_go,
            obstacles=obstacles,
            p_detect=p_detect,
            rays_per_pi=rays_per_pi,
            sensor_speed=sensor_speed,
            sensor_types=sensor_types,
            target_speed=target_speed,
        )

        return scenario_spec
