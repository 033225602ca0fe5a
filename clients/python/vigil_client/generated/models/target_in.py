from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from typing import cast


T = TypeVar("T", bound="TargetIn")


@_attrs_define
class TargetIn:
    """A reported target.

    Attributes:
        vx (float): East displacement per step.
        vy (float): North displacement per step.
        x (float): East coordinate now.
        y (float): North coordinate now.
        id (float | None | str | Unset):
    """

    vx: float
    vy: float
    x: float
    y: float
    id: float | None | str | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        vx = self.vx

        vy = self.vy

        x = self.x

        y = self.y

        id: float | None | str | Unset
        if isinstance(self.id, Unset):
            id = UNSET
        else:
            id = self.id

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "vx": vx,
                "vy": vy,
                "x": x,
                "y": y,
            }
        )
        if id is not UNSET:
            field_dict["id"] = id

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        vx = d.pop("vx")

        vy = d.pop("vy")

        x = d.pop("x")

        y = d.pop("y")

        def _parse_id(data: object) -> float | None | str | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | str | Unset, data)

        id = _parse_id(d.pop("id", UNSET))

        target_in = cls(
            vx=vx,
            vy=vy,
            x=x,
            y=y,
            id=id,
        )

        return target_in
