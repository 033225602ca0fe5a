from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define


from ..models.fov_spec_type_1_shape import FovSpecType1Shape


T = TypeVar("T", bound="FovSpecType1")


@_attrs_define
class FovSpecType1:
    """A disk of the given radius (the paper's future work).

    Attributes:
        radius (float): Radius of the disk.
        shape (FovSpecType1Shape):
    """

    radius: float
    shape: FovSpecType1Shape

    def to_dict(self) -> dict[str, Any]:
        radius = self.radius

        shape = self.shape.value

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "radius": radius,
                "shape": shape,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        radius = d.pop("radius")

        shape = FovSpecType1Shape(d.pop("shape"))

        fov_spec_type_1 = cls(
            radius=radius,
            shape=shape,
        )

        return fov_spec_type_1
