from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define


from typing import cast


T = TypeVar("T", bound="DetectionIn")


@_attrs_define
class DetectionIn:
    """A target detected at a step.

    Attributes:
        id (float | str): A sensor or target id: a string or a number, echoed back as given. Two
            ids are the same when they are the same JSON value: `"7"` and `7`
            differ, `7` and `7.0` do not (JSON has one number type).
        vx (float): East displacement per step.
        vy (float): North displacement per step.
        x (float): East coordinate.
        y (float): North coordinate.
    """

    id: float | str
    vx: float
    vy: float
    x: float
    y: float

    def to_dict(self) -> dict[str, Any]:
        id: float | str
        id = self.id

        vx = self.vx

        vy = self.vy

        x = self.x

        y = self.y

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "id": id,
                "vx": vx,
                "vy": vy,
                "x": x,
                "y": y,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)

        def _parse_id(data: object) -> float | str:
            return cast(float | str, data)

        id = _parse_id(d.pop("id"))

        vx = d.pop("vx")

        vy = d.pop("vy")

        x = d.pop("x")

        y = d.pop("y")

        detection_in = cls(
            id=id,
            vx=vx,
            vy=vy,
            x=x,
            y=y,
        )

        return detection_in
