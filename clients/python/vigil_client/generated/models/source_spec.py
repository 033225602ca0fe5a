from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from ..models.heading import Heading
from typing import cast

if TYPE_CHECKING:
    from ..models.speed_spec import SpeedSpec


T = TypeVar("T", bound="SourceSpec")


@_attrs_define
class SourceSpec:
    """A point source of targets outside the zone.

    Attributes:
        rate (float): Poisson rate, targets per step.
        x (float): East coordinate, within ±1e12 (`MAX_SOURCE_COORDINATE`).
        y (float): North coordinate, within ±1e12.
        direction (float | None | Unset): Centre of the takeoff cone, degrees counter-clockwise from east
            (east 0, north 90, west 180, south 270); the heading's by default.
        heading (Heading | None | Unset):
        speeds (list[SpeedSpec] | None | Unset): Speed distribution, 1 to 8 classes; the scenario's `target_speed`
            by default.
        spread (float | None | Unset): Width of the takeoff cone, degrees, in (0, 180]; 180 by default.
    """

    rate: float
    x: float
    y: float
    direction: float | None | Unset = UNSET
    heading: Heading | None | Unset = UNSET
    speeds: list[SpeedSpec] | None | Unset = UNSET
    spread: float | None | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        rate = self.rate

        x = self.x

        y = self.y

        direction: float | None | Unset
        if isinstance(self.direction, Unset):
            direction = UNSET
        else:
            direction = self.direction

        heading: None | str | Unset
        if isinstance(self.heading, Unset):
            heading = UNSET
        elif isinstance(self.heading, Heading):
            heading = self.heading.value
        else:
            heading = self.heading

        speeds: list[dict[str, Any]] | None | Unset
        if isinstance(self.speeds, Unset):
            speeds = UNSET
        elif isinstance(self.speeds, list):
            speeds = []
            for speeds_type_0_item_data in self.speeds:
                speeds_type_0_item = speeds_type_0_item_data.to_dict()
                speeds.append(speeds_type_0_item)

        else:
            speeds = self.speeds

        spread: float | None | Unset
        if isinstance(self.spread, Unset):
            spread = UNSET
        else:
            spread = self.spread

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "rate": rate,
                "x": x,
                "y": y,
            }
        )
        if direction is not UNSET:
            field_dict["direction"] = direction
        if heading is not UNSET:
            field_dict["heading"] = heading
        if speeds is not UNSET:
            field_dict["speeds"] = speeds
        if spread is not UNSET:
            field_dict["spread"] = spread

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.speed_spec import SpeedSpec  # noqa: PLC0415

        d = dict(src_dict)
        rate = d.pop("rate")

        x = d.pop("x")

        y = d.pop("y")

        def _parse_direction(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        direction = _parse_direction(d.pop("direction", UNSET))

        def _parse_heading(data: object) -> Heading | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, str):
                    raise TypeError()
                heading_type_0 = Heading(data)

                return heading_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(Heading | None | Unset, data)

        heading = _parse_heading(d.pop("heading", UNSET))

        def _parse_speeds(data: object) -> list[SpeedSpec] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                speeds_type_0 = []
                _speeds_type_0 = data
                for speeds_type_0_item_data in _speeds_type_0:
                    speeds_type_0_item = SpeedSpec.from_dict(speeds_type_0_item_data)

                    speeds_type_0.append(speeds_type_0_item)

                return speeds_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[SpeedSpec] | None | Unset, data)

        speeds = _parse_speeds(d.pop("speeds", UNSET))

        def _parse_spread(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        spread = _parse_spread(d.pop("spread", UNSET))

        source_spec = cls(
            rate=rate,
            x=x,
            y=y,
            direction=direction,
            heading=heading,
            speeds=speeds,
            spread=spread,
        )

        return source_spec
