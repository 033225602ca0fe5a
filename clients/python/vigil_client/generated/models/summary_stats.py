from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define
from attrs import field as _attrs_field


T = TypeVar("T", bound="SummaryStats")


@_attrs_define
class SummaryStats:
    """Scalar results of a scenario's precomputation.

    Attributes:
        expected_targets_in_zone (float): Stationary expected number of targets inside the zone.
        precompute_ms (float): Time the precomputation took, milliseconds.
    """

    expected_targets_in_zone: float
    precompute_ms: float
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        expected_targets_in_zone = self.expected_targets_in_zone

        precompute_ms = self.precompute_ms

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "expected_targets_in_zone": expected_targets_in_zone,
                "precompute_ms": precompute_ms,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        expected_targets_in_zone = d.pop("expected_targets_in_zone")

        precompute_ms = d.pop("precompute_ms")

        summary_stats = cls(
            expected_targets_in_zone=expected_targets_in_zone,
            precompute_ms=precompute_ms,
        )

        summary_stats.additional_properties = d
        return summary_stats

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
