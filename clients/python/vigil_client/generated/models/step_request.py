from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from ..models.coordination import Coordination
from ..models.estimator_kind import EstimatorKind
from ..models.objective import Objective
from typing import cast

if TYPE_CHECKING:
    from ..models.sensor_in import SensorIn
    from ..models.target_in import TargetIn


T = TypeVar("T", bound="StepRequest")


@_attrs_define
class StepRequest:
    """Body of a session's step.

    Attributes:
        sensors (list[SensorIn]): Sensors now.
        budget_ms (int | None | Unset): With `coordination: joint`: the most time the step's plan may take,
            milliseconds (1..=1000, 20 by default).
        certify (bool | None | Unset): Certify this step's plan; the session's setting by default.
        coordination (Coordination | None | Unset):
        detections (list[TargetIn] | Unset): Targets detected this step (by any sensor), their position and
            displacement per step now; with an `id` when the client tracks
            identities.
        estimator (EstimatorKind | None | Unset):
        explain (bool | None | Unset): Include the search values in the response.
        gap_target (float | None | Unset): With `coordination: joint`: the certified gap at which it stops, in
            `[0, 1]`; 0.001 by default.
        horizon (int | None | Unset): Horizon T of this step; the session's by default.
        min_separation (int | None | Unset): Minimum separation of this step; the session's by default.
        objective (None | Objective | Unset):
    """

    sensors: list[SensorIn]
    budget_ms: int | None | Unset = UNSET
    certify: bool | None | Unset = UNSET
    coordination: Coordination | None | Unset = UNSET
    detections: list[TargetIn] | Unset = UNSET
    estimator: EstimatorKind | None | Unset = UNSET
    explain: bool | None | Unset = UNSET
    gap_target: float | None | Unset = UNSET
    horizon: int | None | Unset = UNSET
    min_separation: int | None | Unset = UNSET
    objective: None | Objective | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        sensors = []
        for sensors_item_data in self.sensors:
            sensors_item = sensors_item_data.to_dict()
            sensors.append(sensors_item)

        budget_ms: int | None | Unset
        if isinstance(self.budget_ms, Unset):
            budget_ms = UNSET
        else:
            budget_ms = self.budget_ms

        certify: bool | None | Unset
        if isinstance(self.certify, Unset):
            certify = UNSET
        else:
            certify = self.certify

        coordination: None | str | Unset
        if isinstance(self.coordination, Unset):
            coordination = UNSET
        elif isinstance(self.coordination, Coordination):
            coordination = self.coordination.value
        else:
            coordination = self.coordination

        detections: list[dict[str, Any]] | Unset = UNSET
        if not isinstance(self.detections, Unset):
            detections = []
            for detections_item_data in self.detections:
                detections_item = detections_item_data.to_dict()
                detections.append(detections_item)

        estimator: None | str | Unset
        if isinstance(self.estimator, Unset):
            estimator = UNSET
        elif isinstance(self.estimator, EstimatorKind):
            estimator = self.estimator.value
        else:
            estimator = self.estimator

        explain: bool | None | Unset
        if isinstance(self.explain, Unset):
            explain = UNSET
        else:
            explain = self.explain

        gap_target: float | None | Unset
        if isinstance(self.gap_target, Unset):
            gap_target = UNSET
        else:
            gap_target = self.gap_target

        horizon: int | None | Unset
        if isinstance(self.horizon, Unset):
            horizon = UNSET
        else:
            horizon = self.horizon

        min_separation: int | None | Unset
        if isinstance(self.min_separation, Unset):
            min_separation = UNSET
        else:
            min_separation = self.min_separation

        objective: None | str | Unset
        if isinstance(self.objective, Unset):
            objective = UNSET
        elif isinstance(self.objective, Objective):
            objective = self.objective.value
        else:
            objective = self.objective

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "sensors": sensors,
            }
        )
        if budget_ms is not UNSET:
            field_dict["budget_ms"] = budget_ms
        if certify is not UNSET:
            field_dict["certify"] = certify
        if coordination is not UNSET:
            field_dict["coordination"] = coordination
        if detections is not UNSET:
            field_dict["detections"] = detections
        if estimator is not UNSET:
            field_dict["estimator"] = estimator
        if explain is not UNSET:
            field_dict["explain"] = explain
        if gap_target is not UNSET:
            field_dict["gap_target"] = gap_target
        if horizon is not UNSET:
            field_dict["horizon"] = horizon
        if min_separation is not UNSET:
            field_dict["min_separation"] = min_separation
        if objective is not UNSET:
            field_dict["objective"] = objective

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.sensor_in import SensorIn  # noqa: PLC0415
        from ..models.target_in import TargetIn  # noqa: PLC0415

        d = dict(src_dict)
        sensors = []
        _sensors = d.pop("sensors")
        for sensors_item_data in _sensors:
            sensors_item = SensorIn.from_dict(sensors_item_data)

            sensors.append(sensors_item)

        def _parse_budget_ms(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        budget_ms = _parse_budget_ms(d.pop("budget_ms", UNSET))

        def _parse_certify(data: object) -> bool | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(bool | None | Unset, data)

        certify = _parse_certify(d.pop("certify", UNSET))

        def _parse_coordination(data: object) -> Coordination | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, str):
                    raise TypeError()
                coordination_type_0 = Coordination(data)

                return coordination_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(Coordination | None | Unset, data)

        coordination = _parse_coordination(d.pop("coordination", UNSET))

        _detections = d.pop("detections", UNSET)
        detections: list[TargetIn] | Unset = UNSET
        if _detections is not UNSET:
            detections = []
            for detections_item_data in _detections:
                detections_item = TargetIn.from_dict(detections_item_data)

                detections.append(detections_item)

        def _parse_estimator(data: object) -> EstimatorKind | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, str):
                    raise TypeError()
                estimator_type_0 = EstimatorKind(data)

                return estimator_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(EstimatorKind | None | Unset, data)

        estimator = _parse_estimator(d.pop("estimator", UNSET))

        def _parse_explain(data: object) -> bool | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(bool | None | Unset, data)

        explain = _parse_explain(d.pop("explain", UNSET))

        def _parse_gap_target(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        gap_target = _parse_gap_target(d.pop("gap_target", UNSET))

        def _parse_horizon(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        horizon = _parse_horizon(d.pop("horizon", UNSET))

        def _parse_min_separation(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        min_separation = _parse_min_separation(d.pop("min_separation", UNSET))

        def _parse_objective(data: object) -> None | Objective | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, str):
                    raise TypeError()
                objective_type_0 = Objective(data)

                return objective_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | Objective | Unset, data)

        objective = _parse_objective(d.pop("objective", UNSET))

        step_request = cls(
            sensors=sensors,
            budget_ms=budget_ms,
            certify=certify,
            coordination=coordination,
            detections=detections,
            estimator=estimator,
            explain=explain,
            gap_target=gap_target,
            horizon=horizon,
            min_separation=min_separation,
            objective=objective,
        )

        return step_request
