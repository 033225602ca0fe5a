from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from typing import cast


T = TypeVar("T", bound="SensorIn")


@_attrs_define
class SensorIn:
    """A sensor's current position.

    Attributes:
        id (float | str): A sensor or target id: a string or a number, echoed back as given. Two
            ids are the same when they are the same JSON value: `"7"` and `7`
            differ, `7` and `7.0` do not (JSON has one number type).
        x (float): East coordinate.
        y (float): North coordinate.
        type_ (None | str | Unset): Its sensor type (a name of the scenario's `sensor_types`);
            `default` by default.
    """

    id: float | str
    x: float
    y: float
    type_: None | str | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        id: float | str
        id = self.id

        x = self.x

        y = self.y

        type_: None | str | Unset
        if isinstance(self.type_, Unset):
            type_ = UNSET
        else:
            type_ = self.type_

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "id": id,
                "x": x,
                "y": y,
            }
        )
        if type_ is not UNSET:
            field_dict["type"] = type_

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)

        def _parse_id(data: object) -> float | str:
            return cast(float | str, data)

        id = _parse_id(d.pop("id"))

        x = d.pop("x")

        y = d.pop("y")

        def _parse_type_(data: object) -> None | str | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(None | str | Unset, data)

        type_ = _parse_type_(d.pop("type", UNSET))

        sensor_in = cls(
            id=id,
            x=x,
            y=y,
            type_=type_,
        )

        return sensor_in
