from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define
from attrs import field as _attrs_field


T = TypeVar("T", bound="Bound")


@_attrs_define
class Bound:
    """An upper bound on the best joint plan's value, beside a plan's value.

    Attributes:
        gap (float): `(upper − value) / upper` for the plan's value (0 when `upper` is
            0): the plan is within this fraction of the best joint plan.
        upper (float): No joint plan (one legal path per sensor, the minimum separation
            ignored) expects more detections over steps 1..=T than this.
    """

    gap: float
    upper: float
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        gap = self.gap

        upper = self.upper

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "gap": gap,
                "upper": upper,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        gap = d.pop("gap")

        upper = d.pop("upper")

        bound = cls(
            gap=gap,
            upper=upper,
        )

        bound.additional_properties = d
        return bound

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
