from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define


T = TypeVar("T", bound="NoGoSpec")


@_attrs_define
class NoGoSpec:
    """A rectangle of ground no sensor may stand on, in zone coordinates.

    Attributes:
        x0 (float): West edge.
        x1 (float): East edge (> x0).
        y0 (float): South edge.
        y1 (float): North edge (> y0).
    """

    x0: float
    x1: float
    y0: float
    y1: float

    def to_dict(self) -> dict[str, Any]:
        x0 = self.x0

        x1 = self.x1

        y0 = self.y0

        y1 = self.y1

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "x0": x0,
                "x1": x1,
                "y0": y0,
                "y1": y1,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        x0 = d.pop("x0")

        x1 = d.pop("x1")

        y0 = d.pop("y0")

        y1 = d.pop("y1")

        no_go_spec = cls(
            x0=x0,
            x1=x1,
            y0=y0,
            y1=y1,
        )

        return no_go_spec
