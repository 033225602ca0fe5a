from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
    from ..models.cell_out import CellOut
    from ..models.explain import Explain


T = TypeVar("T", bound="PlanOut")


@_attrs_define
class PlanOut:
    """One sensor's plan.

    Attributes:
        expected_detections (float): The value its final search maximised (for `first_detections`, the
            first detections its path adds to those it planned against).
        path (list[CellOut]): Cells at steps 1..=T.
        priority (int): Rank, 1 = highest.
        sensor (float | str): A sensor or target id: a string or a number, echoed back as given. Two
            ids are the same when they are the same JSON value: `"7"` and `7`
            differ, `7` and `7.0` do not (JSON has one number type).
        separation_violations (int): The (step, other sensor) pairs at which its path is closer to
            another sensor's than `min_separation` allows.
        start (CellOut): A lattice cell and its centre.
        explain (Explain | None | Unset):
    """

    expected_detections: float
    path: list[CellOut]
    priority: int
    sensor: float | str
    separation_violations: int
    start: CellOut
    explain: Explain | None | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        from ..models.explain import Explain  # noqa: PLC0415

        expected_detections = self.expected_detections

        path = []
        for path_item_data in self.path:
            path_item = path_item_data.to_dict()
            path.append(path_item)

        priority = self.priority

        sensor: float | str
        sensor = self.sensor

        separation_violations = self.separation_violations

        start = self.start.to_dict()

        explain: dict[str, Any] | None | Unset
        if isinstance(self.explain, Unset):
            explain = UNSET
        elif isinstance(self.explain, Explain):
            explain = self.explain.to_dict()
        else:
            explain = self.explain

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "expected_detections": expected_detections,
                "path": path,
                "priority": priority,
                "sensor": sensor,
                "separation_violations": separation_violations,
                "start": start,
            }
        )
        if explain is not UNSET:
            field_dict["explain"] = explain

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.cell_out import CellOut  # noqa: PLC0415
        from ..models.explain import Explain  # noqa: PLC0415

        d = dict(src_dict)
        expected_detections = d.pop("expected_detections")

        path = []
        _path = d.pop("path")
        for path_item_data in _path:
            path_item = CellOut.from_dict(path_item_data)

            path.append(path_item)

        priority = d.pop("priority")

        def _parse_sensor(data: object) -> float | str:
            return cast(float | str, data)

        sensor = _parse_sensor(d.pop("sensor"))

        separation_violations = d.pop("separation_violations")

        start = CellOut.from_dict(d.pop("start"))

        def _parse_explain(data: object) -> Explain | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                explain_type_0 = Explain.from_dict(data)

                return explain_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(Explain | None | Unset, data)

        explain = _parse_explain(d.pop("explain", UNSET))

        plan_out = cls(
            expected_detections=expected_detections,
            path=path,
            priority=priority,
            sensor=sensor,
            separation_violations=separation_violations,
            start=start,
            explain=explain,
        )

        plan_out.additional_properties = d
        return plan_out

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
