from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define


from ..models.fov_spec_type_0_shape import FovSpecType0Shape


T = TypeVar("T", bound="FovSpecType0")


@_attrs_define
class FovSpecType0:
    """The paper's inscribed square, `|dx|, |dy| ≤ half_width`.

    Attributes:
        half_width (float): Half the side of the square.
        shape (FovSpecType0Shape):
    """

    half_width: float
    shape: FovSpecType0Shape

    def to_dict(self) -> dict[str, Any]:
        half_width = self.half_width

        shape = self.shape.value

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "half_width": half_width,
                "shape": shape,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        half_width = d.pop("half_width")

        shape = FovSpecType0Shape(d.pop("shape"))

        fov_spec_type_0 = cls(
            half_width=half_width,
            shape=shape,
        )

        return fov_spec_type_0
