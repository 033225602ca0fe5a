from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from ..models.coordination import Coordination
from ..models.estimator_kind import EstimatorKind
from ..models.observed import Observed
from typing import cast

if TYPE_CHECKING:
    from ..models.scenario_spec import ScenarioSpec


T = TypeVar("T", bound="SessionRequestWithScenario")


@_attrs_define
class SessionRequestWithScenario:
    """`POST /v1/sessions` carrying its scenario.

    Attributes:
        scenario (ScenarioSpec): A scenario as clients send it.
        coordination (Coordination | None | Unset):
        estimator (EstimatorKind | None | Unset):
        history_steps (int | None | Unset): Steps of history kept (0..=128, 16 by default): the sensors'
            past positions planned with, and how long a track lives
            undetected.
        horizon (int | None | Unset): Horizon T of its steps; the scenario's by default.
        min_separation (int | None | Unset): Minimum separation of its steps, cells (0..=16); the
            scenario's by default.
        observed (None | Observed | Unset):
    """

    scenario: ScenarioSpec
    coordination: Coordination | None | Unset = UNSET
    estimator: EstimatorKind | None | Unset = UNSET
    history_steps: int | None | Unset = UNSET
    horizon: int | None | Unset = UNSET
    min_separation: int | None | Unset = UNSET
    observed: None | Observed | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        scenario = self.scenario.to_dict()

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

        history_steps: int | None | Unset
        if isinstance(self.history_steps, Unset):
            history_steps = UNSET
        else:
            history_steps = self.history_steps

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

        observed: None | str | Unset
        if isinstance(self.observed, Unset):
            observed = UNSET
        elif isinstance(self.observed, Observed):
            observed = self.observed.value
        else:
            observed = self.observed

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "scenario": scenario,
            }
        )
        if coordination is not UNSET:
            field_dict["coordination"] = coordination
        if estimator is not UNSET:
            field_dict["estimator"] = estimator
        if history_steps is not UNSET:
            field_dict["history_steps"] = history_steps
        if horizon is not UNSET:
            field_dict["horizon"] = horizon
        if min_separation is not UNSET:
            field_dict["min_separation"] = min_separation
        if observed is not UNSET:
            field_dict["observed"] = observed

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.scenario_spec import ScenarioSpec  # noqa: PLC0415

        d = dict(src_dict)
        scenario = ScenarioSpec.from_dict(d.pop("scenario"))

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

        def _parse_history_steps(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        history_steps = _parse_history_steps(d.pop("history_steps", UNSET))

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

        session_request_with_scenario = cls(
            scenario=scenario,
            coordination=coordination,
            estimator=estimator,
            history_steps=history_steps,
            horizon=horizon,
            min_separation=min_separation,
            observed=observed,
        )

        return session_request_with_scenario
