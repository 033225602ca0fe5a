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
    from ..models.fit_tolerance import FitTolerance


T = TypeVar("T", bound="SessionRequestById")


@_attrs_define
class SessionRequestById:
    """`POST /v1/sessions` naming its scenario.

    Attributes:
        scenario_id (str): Id of a registered scenario, or of one sent inline before. Example: paper-v10.
        certify (bool | None | Unset): Certify each step's plan (true by default; see the plan request's
            `certify`).
        coordination (Coordination | None | Unset):
        estimator (EstimatorKind | None | Unset):
        history_steps (int | None | Unset): Steps of history kept (0..=128, 16 by default): the sensors' past
            positions planned with, and how long a track lives undetected.
        horizon (int | None | Unset): Horizon T; the scenario's by default.
        learn_rates (bool | None | Unset): Learn the sources' rates from the detections (false by default):
            every step then needs an `id` on each detection, folds its looks
            and new targets into each source's posterior (the scenario's prior;
            see `docs/learning.md`), plans with the posterior means and reports
            them as `rates`.
        min_separation (int | None | Unset): Minimum separation between sensors, cells (0..=16); the scenario's
            by default.
        objective (None | Objective | Unset):
        observed (None | Observed | Unset):
        tolerance (FitTolerance | None | Unset):
    """

    scenario_id: str
    certify: bool | None | Unset = UNSET
    coordination: Coordination | None | Unset = UNSET
    estimator: EstimatorKind | None | Unset = UNSET
    history_steps: int | None | Unset = UNSET
    horizon: int | None | Unset = UNSET
    learn_rates: bool | None | Unset = UNSET
    min_separation: int | None | Unset = UNSET
    objective: None | Objective | Unset = UNSET
    observed: None | Observed | Unset = UNSET
    tolerance: FitTolerance | None | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        from ..models.fit_tolerance import FitTolerance  # noqa: PLC0415

        scenario_id = self.scenario_id

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

        learn_rates: bool | None | Unset
        if isinstance(self.learn_rates, Unset):
            learn_rates = UNSET
        else:
            learn_rates = self.learn_rates

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

        tolerance: dict[str, Any] | None | Unset
        if isinstance(self.tolerance, Unset):
            tolerance = UNSET
        elif isinstance(self.tolerance, FitTolerance):
            tolerance = self.tolerance.to_dict()
        else:
            tolerance = self.tolerance

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "scenario_id": scenario_id,
            }
        )
        if certify is not UNSET:
            field_dict["certify"] = certify
        if coordination is not UNSET:
            field_dict["coordination"] = coordination
        if estimator is not UNSET:
            field_dict["estimator"] = estimator
        if history_steps is not UNSET:
            field_dict["history_steps"] = history_steps
        if horizon is not UNSET:
            field_dict["horizon"] = horizon
        if learn_rates is not UNSET:
            field_dict["learn_rates"] = learn_rates
        if min_separation is not UNSET:
            field_dict["min_separation"] = min_separation
        if objective is not UNSET:
            field_dict["objective"] = objective
        if observed is not UNSET:
            field_dict["observed"] = observed
        if tolerance is not UNSET:
            field_dict["tolerance"] = tolerance

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.fit_tolerance import FitTolerance  # noqa: PLC0415

        d = dict(src_dict)
        scenario_id = d.pop("scenario_id")

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

        def _parse_learn_rates(data: object) -> bool | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(bool | None | Unset, data)

        learn_rates = _parse_learn_rates(d.pop("learn_rates", UNSET))

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

        def _parse_tolerance(data: object) -> FitTolerance | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                tolerance_type_0 = FitTolerance.from_dict(data)

                return tolerance_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(FitTolerance | None | Unset, data)

        tolerance = _parse_tolerance(d.pop("tolerance", UNSET))

        session_request_by_id = cls(
            scenario_id=scenario_id,
            certify=certify,
            coordination=coordination,
            estimator=estimator,
            history_steps=history_steps,
            horizon=horizon,
            learn_rates=learn_rates,
            min_separation=min_separation,
            objective=objective,
            observed=observed,
            tolerance=tolerance,
        )

        return session_request_by_id
