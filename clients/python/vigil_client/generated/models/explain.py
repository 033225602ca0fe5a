from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define
from attrs import field as _attrs_field


from typing import cast


T = TypeVar("T", bound="Explain")


@_attrs_define
class Explain:
    """The search values of one sensor.

    Attributes:
        values (list[list[list[float | None]]]): `values[t−1][dr+m·T][dc+m·T]` (m the sensor's speed); null where
            unreachable by step t, blocked or off the lattice. With
            `first_detections` each is the first detections of a look there
            alone (against the history and the looks the sensor planned
            against): a path's stops can hold the same targets, so its value is
            at most the sum of its cells' values, not the sum.
    """

    values: list[list[list[float | None]]]
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        values = []
        for values_item_data in self.values:
            values_item = []
            for values_item_item_data in values_item_data:
                values_item_item = []
                for values_item_item_item_data in values_item_item_data:
                    values_item_item_item: float | None
                    values_item_item_item = values_item_item_item_data
                    values_item_item.append(values_item_item_item)

                values_item.append(values_item_item)

            values.append(values_item)

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "values": values,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        values = []
        _values = d.pop("values")
        for values_item_data in _values:
            values_item = []
            _values_item = values_item_data
            for values_item_item_data in _values_item:
                values_item_item = []
                _values_item_item = values_item_item_data
                for values_item_item_item_data in _values_item_item:

                    def _parse_values_item_item_item(data: object) -> float | None:
                        if data is None:
                            return data
                        return cast(float | None, data)

                    values_item_item_item = _parse_values_item_item_item(
                        values_item_item_item_data
                    )

                    values_item_item.append(values_item_item_item)

                values_item.append(values_item_item)

            values.append(values_item)

        explain = cls(
            values=values,
        )

        explain.additional_properties = d
        return explain

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
