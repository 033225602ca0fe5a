from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define
from attrs import field as _attrs_field


from ..models.estimator_kind import EstimatorKind
from ..models.objective import Objective
from typing import cast

if TYPE_CHECKING:
    from ..models.sensor_score import SensorScore


T = TypeVar("T", bound="EvaluateResponse")


@_attrs_define
class EvaluateResponse:
    """Response of an evaluate request.

    Attributes:
        estimator (EstimatorKind): Which estimator of `n̂(k,t)` to use.
        expected_by_step (list[float]): The same per step (for `first_detections`: detected for the first
            time at that step).
        expected_detections (float): Expected distinct targets detected over steps 1..=T (for
            `first_detections`: targets not yet detected that the paths detect
            at least once).
        horizon (int): Horizon T of the paths.
        min_separation (int): Minimum separation counted, cells (0: none).
        objective (Objective): What a plan maximises.
        scenario (str): Scenario id.
        sensors (list[SensorScore]): Per sensor, in the order of `sensors`.
        separation_violations (int): The (step, pair of sensors) at which two paths are closer than
            `min_separation` allows.
    """

    estimator: EstimatorKind
    expected_by_step: list[float]
    expected_detections: float
    horizon: int
    min_separation: int
    objective: Objective
    scenario: str
    sensors: list[SensorScore]
    separation_violations: int
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        estimator = self.estimator.value

        expected_by_step = self.expected_by_step

        expected_detections = self.expected_detections

        horizon = self.horizon

        min_separation = self.min_separation

        objective = self.objective.value

        scenario = self.scenario

        sensors = []
        for sensors_item_data in self.sensors:
            sensors_item = sensors_item_data.to_dict()
            sensors.append(sensors_item)

        separation_violations = self.separation_violations

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "estimator": estimator,
                "expected_by_step": expected_by_step,
                "expected_detections": expected_detections,
                "horizon": horizon,
                "min_separation": min_separation,
                "objective": objective,
                "scenario": scenario,
                "sensors": sensors,
                "separation_violations": separation_violations,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.sensor_score import SensorScore  # noqa: PLC0415

        d = dict(src_dict)
        estimator = EstimatorKind(d.pop("estimator"))

        expected_by_step = cast(list[float], d.pop("expected_by_step"))

        expected_detections = d.pop("expected_detections")

        horizon = d.pop("horizon")

        min_separation = d.pop("min_separation")

        objective = Objective(d.pop("objective"))

        scenario = d.pop("scenario")

        sensors = []
        _sensors = d.pop("sensors")
        for sensors_item_data in _sensors:
            sensors_item = SensorScore.from_dict(sensors_item_data)

            sensors.append(sensors_item)

        separation_violations = d.pop("separation_violations")

        evaluate_response = cls(
            estimator=estimator,
            expected_by_step=expected_by_step,
            expected_detections=expected_detections,
            horizon=horizon,
            min_separation=min_separation,
            objective=objective,
            scenario=scenario,
            sensors=sensors,
            separation_violations=separation_violations,
        )

        evaluate_response.additional_properties = d
        return evaluate_response

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
