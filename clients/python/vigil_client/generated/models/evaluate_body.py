from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from ..models.coordination import Coordination
from ..models.estimator_kind import EstimatorKind
from ..models.objective import Objective
from ..models.observed import Observed
from typing import cast

if TYPE_CHECKING:
    from ..models.position_in import PositionIn
    from ..models.sensor_in import SensorIn
    from ..models.sensor_path_in import SensorPathIn
    from ..models.target_in import TargetIn


T = TypeVar("T", bound="EvaluateBody")


@_attrs_define
class EvaluateBody:
    """Body of `POST /v1/scenarios/{id}/evaluate`: a plan request's fields
    (its `coordination`, `explain`, `gap_target`, `budget_ms` and
    `certify` are checked as a plan checks them, so a plan's body
    scores as sent, and play no part) and the paths to score.

        Attributes:
            paths (list[SensorPathIn]): One path per sensor.
            sensors (list[SensorIn]): Sensors now.
            budget_ms (int | None | Unset): With `coordination: joint`: the time after which its
                rounds past `iterated` stop, milliseconds (1..=1000, 20 by
                default), counted from the plan's start; the `iterated`
                plan they start from is always finished.
            certify (bool | None | Unset): Certify the plan (`bound`, exact plans; true by default):
                `false` skips the certificate's work and leaves `bound`
                out; refused with `coordination: joint`.
            coordination (Coordination | None | Unset):
            estimator (EstimatorKind | None | Unset):
            explain (bool | None | Unset): Include the search values in the response.
            gap_target (float | None | Unset): With `coordination: joint`: the certified gap at which it
                stops, in `[0, 1]`; 0.001 by default.
            history (list[list[PositionIn]] | None | Unset): Sensors' positions 1, 2, … steps ago (at most 256 a step).
            horizon (int | None | Unset): Horizon T; the scenario's by default.
            min_separation (int | None | Unset): Minimum separation between sensors at every step, cells
                (Chebyshev distance; 0..=16, 0 = no rule); the scenario's by
                default. Kept wherever it can be: a sensor that cannot keep
                it takes the path with the fewest violations, which the
                response counts.
            objective (None | Objective | Unset):
            observed (None | Observed | Unset):
            targets (list[TargetIn] | Unset): Targets reported now.
    """

    paths: list[SensorPathIn]
    sensors: list[SensorIn]
    budget_ms: int | None | Unset = UNSET
    certify: bool | None | Unset = UNSET
    coordination: Coordination | None | Unset = UNSET
    estimator: EstimatorKind | None | Unset = UNSET
    explain: bool | None | Unset = UNSET
    gap_target: float | None | Unset = UNSET
    history: list[list[PositionIn]] | None | Unset = UNSET
    horizon: int | None | Unset = UNSET
    min_separation: int | None | Unset = UNSET
    objective: None | Objective | Unset = UNSET
    observed: None | Observed | Unset = UNSET
    targets: list[TargetIn] | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        paths = []
        for paths_item_data in self.paths:
            paths_item = paths_item_data.to_dict()
            paths.append(paths_item)

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

        history: list[list[dict[str, Any]]] | None | Unset
        if isinstance(self.history, Unset):
            history = UNSET
        elif isinstance(self.history, list):
            history = []
            for history_type_0_item_data in self.history:
                history_type_0_item = []
                for history_type_0_item_item_data in history_type_0_item_data:
                    history_type_0_item_item = history_type_0_item_item_data.to_dict()
                    history_type_0_item.append(history_type_0_item_item)

                history.append(history_type_0_item)

        else:
            history = self.history

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

        observed: None | str | Unset
        if isinstance(self.observed, Unset):
            observed = UNSET
        elif isinstance(self.observed, Observed):
            observed = self.observed.value
        else:
            observed = self.observed

        targets: list[dict[str, Any]] | Unset = UNSET
        if not isinstance(self.targets, Unset):
            targets = []
            for targets_item_data in self.targets:
                targets_item = targets_item_data.to_dict()
                targets.append(targets_item)

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "paths": paths,
                "sensors": sensors,
            }
        )
        if budget_ms is not UNSET:
            field_dict["budget_ms"] = budget_ms
        if certify is not UNSET:
            field_dict["certify"] = certify
        if coordination is not UNSET:
            field_dict["coordination"] = coordination
        if estimator is not UNSET:
            field_dict["estimator"] = estimator
        if explain is not UNSET:
            field_dict["explain"] = explain
        if gap_target is not UNSET:
            field_dict["gap_target"] = gap_target
        if history is not UNSET:
            field_dict["history"] = history
        if horizon is not UNSET:
            field_dict["horizon"] = horizon
        if min_separation is not UNSET:
            field_dict["min_separation"] = min_separation
        if objective is not UNSET:
            field_dict["objective"] = objective
        if observed is not UNSET:
            field_dict["observed"] = observed
        if targets is not UNSET:
            field_dict["targets"] = targets

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.position_in import PositionIn  # noqa: PLC0415
        from ..models.sensor_in import SensorIn  # noqa: PLC0415
        from ..models.sensor_path_in import SensorPathIn  # noqa: PLC0415
        from ..models.target_in import TargetIn  # noqa: PLC0415

        d = dict(src_dict)
        paths = []
        _paths = d.pop("paths")
        for paths_item_data in _paths:
            paths_item = SensorPathIn.from_dict(paths_item_data)

            paths.append(paths_item)

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

        def _parse_history(data: object) -> list[list[PositionIn]] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                history_type_0 = []
                _history_type_0 = data
                for history_type_0_item_data in _history_type_0:
                    history_type_0_item = []
                    _history_type_0_item = history_type_0_item_data
                    for history_type_0_item_item_data in _history_type_0_item:
                        history_type_0_item_item = PositionIn.from_dict(
                            history_type_0_item_item_data
                        )

                        history_type_0_item.append(history_type_0_item_item)

                    history_type_0.append(history_type_0_item)

                return history_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[list[PositionIn]] | None | Unset, data)

        history = _parse_history(d.pop("history", UNSET))

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

        def _parse_observed(data: object) -> None | Observed | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, str):
                    raise TypeError()
                observed_type_0 = Observed(data)

                return observed_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | Observed | Unset, data)

        observed = _parse_observed(d.pop("observed", UNSET))

        _targets = d.pop("targets", UNSET)
        targets: list[TargetIn] | Unset = UNSET
        if _targets is not UNSET:
            targets = []
            for targets_item_data in _targets:
                targets_item = TargetIn.from_dict(targets_item_data)

                targets.append(targets_item)

        evaluate_body = cls(
            paths=paths,
            sensors=sensors,
            budget_ms=budget_ms,
            certify=certify,
            coordination=coordination,
            estimator=estimator,
            explain=explain,
            gap_target=gap_target,
            history=history,
            horizon=horizon,
            min_separation=min_separation,
            objective=objective,
            observed=observed,
            targets=targets,
        )

        return evaluate_body
