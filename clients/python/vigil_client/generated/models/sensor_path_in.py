from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define


from typing import cast

if TYPE_CHECKING:
    from ..models.cell_in import CellIn


T = TypeVar("T", bound="SensorPathIn")


@_attrs_define
class SensorPathIn:
    """One sensor's path to score.

    Attributes:
        path (list[CellIn]): Its cells at steps 1..=T.
        sensor (float | str): A sensor or target id: a string or a number, echoed back as given. Two
            ids are the same when they are the same JSON value: `"7"` and `7`
            differ, `7` and `7.0` do not (JSON has one number type).
    """

    path: list[CellIn]
    sensor: float | str

    def to_dict(self) -> dict[str, Any]:
        path = []
        for path_item_data in self.path:
            path_item = path_item_data.to_dict()
            path.append(path_item)

        sensor: float | str
        sensor = self.sensor

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "path": path,
                "sensor": sensor,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.cell_in import CellIn  # noqa: PLC0415

        d = dict(src_dict)
        path = []
        _path = d.pop("path")
        for path_item_data in _path:
            path_item = CellIn.from_dict(path_item_data)

            path.append(path_item)

        def _parse_sensor(data: object) -> float | str:
            return cast(float | str, data)

        sensor = _parse_sensor(d.pop("sensor"))

        sensor_path_in = cls(
            path=path,
            sensor=sensor,
        )

        return sensor_path_in
