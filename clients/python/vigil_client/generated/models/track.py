from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast


T = TypeVar("T", bound="Track")


@_attrs_define
class Track:
    """A target the session follows: its last detection moved on along its
    straight line.

        Attributes:
            last_detected (int): The step it was last detected at.
            vx (float): East displacement per step.
            vy (float): North displacement per step.
            x (float): East coordinate now.
            y (float): North coordinate now.
            id (float | None | str | Unset):
    """

    last_detected: int
    vx: float
    vy: float
    x: float
    y: float
    id: float | None | str | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        last_detected = self.last_detected

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
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "last_detected": last_detected,
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
        last_detected = d.pop("last_detected")

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

        track = cls(
            last_detected=last_detected,
            vx=vx,
            vy=vy,
            x=x,
            y=y,
            id=id,
        )

        track.additional_properties = d
        return track

    @property
    def additional_keys(self) -> list[str]:
        return list(self.additional_properties.keys())

    def __getitem__(self, key: str) -> Any:
        return self.additional_properties[key]

    def __setitem__(self, key: str, value: Any) -> None:
        self.additional_properties[key] = value

    def __delitem__(self, key: str) -> None:
        del self.additional_properties[key]

    def __contains__(self, key: str) -> bool:
        return key in self.additional_properties
