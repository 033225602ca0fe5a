from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
    from ..models.detection_in import DetectionIn
    from ..models.sensor_in import SensorIn


T = TypeVar("T", bound="FitStep")


@_attrs_define
class FitStep:
    """One step of a fit window: the looks taken and what they detected.

    Attributes:
        detections (list[DetectionIn] | Unset): The targets detected at this step (at most 20,000).
        sensors (list[SensorIn] | Unset): The sensors' positions at this step (snapped to cell centres, as in
            a plan): each took a look with its type's field of view.
        step (int | None | Unset): The step's number (optional): when given, each step's must be the
            previous step's plus one.
    """

    detections: list[DetectionIn] | Unset = UNSET
    sensors: list[SensorIn] | Unset = UNSET
    step: int | None | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        detections: list[dict[str, Any]] | Unset = UNSET
        if not isinstance(self.detections, Unset):
            detections = []
            for detections_item_data in self.detections:
                detections_item = detections_item_data.to_dict()
                detections.append(detections_item)

        sensors: list[dict[str, Any]] | Unset = UNSET
        if not isinstance(self.sensors, Unset):
            sensors = []
            for sensors_item_data in self.sensors:
                sensors_item = sensors_item_data.to_dict()
                sensors.append(sensors_item)

        step: int | None | Unset
        if isinstance(self.step, Unset):
            step = UNSET
        else:
            step = self.step

        field_dict: dict[str, Any] = {}

        field_dict.update({})
        if detections is not UNSET:
            field_dict["detections"] = detections
        if sensors is not UNSET:
            field_dict["sensors"] = sensors
        if step is not UNSET:
            field_dict["step"] = step

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.detection_in import DetectionIn  # noqa: PLC0415
        from ..models.sensor_in import SensorIn  # noqa: PLC0415

        d = dict(src_dict)
        _detections = d.pop("detections", UNSET)
        detections: list[DetectionIn] | Unset = UNSET
        if _detections is not UNSET:
            detections = []
            for detections_item_data in _detections:
                detections_item = DetectionIn.from_dict(detections_item_data)

                detections.append(detections_item)

        _sensors = d.pop("sensors", UNSET)
        sensors: list[SensorIn] | Unset = UNSET
        if _sensors is not UNSET:
            sensors = []
            for sensors_item_data in _sensors:
                sensors_item = SensorIn.from_dict(sensors_item_data)

                sensors.append(sensors_item)

        def _parse_step(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        step = _parse_step(d.pop("step", UNSET))

        fit_step = cls(
            detections=detections,
            sensors=sensors,
            step=step,
        )

        return fit_step
