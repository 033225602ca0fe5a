from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define


T = TypeVar("T", bound="SpeedSpec")


@_attrs_define
class SpeedSpec:
    """One speed of a source's speed distribution.

    Attributes:
        speed (float): Distance a target of this class flies per step.
        weight (float): Relative weight; a source's weights are normalised by their sum.
    """

    speed: float
    weight: float

    def to_dict(self) -> dict[str, Any]:
        speed = self.speed

        weight = self.weight

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "speed": speed,
                "weight": weight,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        speed = d.pop("speed")

        weight = d.pop("weight")

        speed_spec = cls(
            speed=speed,
            weight=weight,
        )

        return speed_spec
