from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define
from attrs import field as _attrs_field


from typing import cast


T = TypeVar("T", bound="SensorScore")


@_attrs_define
class SensorScore:
    """One sensor's share of a scored set of paths.

    Attributes:
        marginal (float): What the total loses without this sensor's path.
        sensor (float | str): A sensor or target id: a string or a number, echoed back as given. Two
            ids are the same when they are the same JSON value: `"7"` and `7`
            differ, `7` and `7.0` do not (JSON has one number type).
        separation_violations (int): The (step, other sensor) pairs at which its path is closer to
            another sensor's than `min_separation` allows.
    """

    marginal: float
    sensor: float | str
    separation_violations: int
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        marginal = self.marginal

        sensor: float | str
        sensor = self.sensor

        separation_violations = self.separation_violations

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "marginal": marginal,
                "sensor": sensor,
                "separation_violations": separation_violations,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        marginal = d.pop("marginal")

        def _parse_sensor(data: object) -> float | str:
            return cast(float | str, data)

        sensor = _parse_sensor(d.pop("sensor"))

        separation_violations = d.pop("separation_violations")

        sensor_score = cls(
            marginal=marginal,
            sensor=sensor,
            separation_violations=separation_violations,
        )

        sensor_score.additional_properties = d
        return sensor_score

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
