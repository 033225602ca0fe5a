from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.coordination import Coordination
from ..models.estimator_kind import EstimatorKind
from ..models.objective import Objective
from typing import cast

if TYPE_CHECKING:
    from ..models.bound import Bound
    from ..models.joint_report import JointReport
    from ..models.plan_out import PlanOut
    from ..models.source_rate import SourceRate


T = TypeVar("T", bound="StepResponse")


@_attrs_define
class StepResponse:
    """Body of `POST /v1/sessions/{id}/step`: the plan, and the step's number.

    Attributes:
        compute_micros (int): Planning time, microseconds.
        coordination (Coordination): How sensors' searches are coordinated.
        estimator (EstimatorKind): Which estimator of `n̂(k,t)` to use.
        expected_by_step (list[float]): The same per step (for `first_detections`: the targets detected for
            the first time at that step).
        expected_detections (float): Expected distinct targets detected over steps 1..=T, summed over the
            steps (`detections`), or expected targets not yet detected that the
            plan detects at least once (`first_detections`).
        horizon (int): Horizon T used.
        min_separation (int): Minimum separation kept, cells (0: none).
        objective (Objective): What a plan maximises.
        plans (list[PlanOut]): Plans in request order.
        scenario (str): Scenario id.
        separation_violations (int): The (step, pair of sensors) at which two paths are closer than
            `min_separation` allows, each pair once per step (half the sum of
            the plans' counts).
        step (int): The number of this step (0 for the first).
        bound (Bound | None | Unset):
        joint (JointReport | None | Unset):
        rates (list[SourceRate] | None | Unset): With `learn_rates`: each source's rate learnt up to this step, as
            `POST /v1/scenarios/{id}/fit` gives them (the plan used the
            posterior means).
    """

    compute_micros: int
    coordination: Coordination
    estimator: EstimatorKind
    expected_by_step: list[float]
    expected_detections: float
    horizon: int
    min_separation: int
    objective: Objective
    plans: list[PlanOut]
    scenario: str
    separation_violations: int
    step: int
    bound: Bound | None | Unset = UNSET
    joint: JointReport | None | Unset = UNSET
    rates: list[SourceRate] | None | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        from ..models.bound import Bound  # noqa: PLC0415
        from ..models.joint_report import JointReport  # noqa: PLC0415

        compute_micros = self.compute_micros

        coordination = self.coordination.value

        estimator = self.estimator.value

        expected_by_step = self.expected_by_step

        expected_detections = self.expected_detections

        horizon = self.horizon

        min_separation = self.min_separation

        objective = self.objective.value

        plans = []
        for plans_item_data in self.plans:
            plans_item = plans_item_data.to_dict()
            plans.append(plans_item)

        scenario = self.scenario

        separation_violations = self.separation_violations

        step = self.step

        bound: dict[str, Any] | None | Unset
        if isinstance(self.bound, Unset):
            bound = UNSET
        elif isinstance(self.bound, Bound):
            bound = self.bound.to_dict()
        else:
            bound = self.bound

        joint: dict[str, Any] | None | Unset
        if isinstance(self.joint, Unset):
            joint = UNSET
        elif isinstance(self.joint, JointReport):
            joint = self.joint.to_dict()
        else:
            joint = self.joint

        rates: list[dict[str, Any]] | None | Unset
        if isinstance(self.rates, Unset):
            rates = UNSET
        elif isinstance(self.rates, list):
            rates = []
            for rates_type_0_item_data in self.rates:
                rates_type_0_item = rates_type_0_item_data.to_dict()
                rates.append(rates_type_0_item)

        else:
            rates = self.rates

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "compute_micros": compute_micros,
                "coordination": coordination,
                "estimator": estimator,
                "expected_by_step": expected_by_step,
                "expected_detections": expected_detections,
                "horizon": horizon,
                "min_separation": min_separation,
                "objective": objective,
                "plans": plans,
                "scenario": scenario,
                "separation_violations": separation_violations,
                "step": step,
            }
        )
        if bound is not UNSET:
            field_dict["bound"] = bound
        if joint is not UNSET:
            field_dict["joint"] = joint
        if rates is not UNSET:
            field_dict["rates"] = rates

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.bound import Bound  # noqa: PLC0415
        from ..models.joint_report import JointReport  # noqa: PLC0415
        from ..models.plan_out import PlanOut  # noqa: PLC0415
        from ..models.source_rate import SourceRate  # noqa: PLC0415

        d = dict(src_dict)
        compute_micros = d.pop("compute_micros")

        coordination = Coordination(d.pop("coordination"))

        estimator = EstimatorKind(d.pop("estimator"))

        expected_by_step = cast(list[float], d.pop("expected_by_step"))

        expected_detections = d.pop("expected_detections")

        horizon = d.pop("horizon")

        min_separation = d.pop("min_separation")

        objective = Objective(d.pop("objective"))

        plans = []
        _plans = d.pop("plans")
        for plans_item_data in _plans:
            plans_item = PlanOut.from_dict(plans_item_data)

            plans.append(plans_item)

        scenario = d.pop("scenario")

        separation_violations = d.pop("separation_violations")

        step = d.pop("step")

        def _parse_bound(data: object) -> Bound | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                bound_type_0 = Bound.from_dict(data)

                return bound_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(Bound | None | Unset, data)

        bound = _parse_bound(d.pop("bound", UNSET))

        def _parse_joint(data: object) -> JointReport | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                joint_type_0 = JointReport.from_dict(data)

                return joint_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(JointReport | None | Unset, data)

        joint = _parse_joint(d.pop("joint", UNSET))

        def _parse_rates(data: object) -> list[SourceRate] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                rates_type_0 = []
                _rates_type_0 = data
                for rates_type_0_item_data in _rates_type_0:
                    rates_type_0_item = SourceRate.from_dict(rates_type_0_item_data)

                    rates_type_0.append(rates_type_0_item)

                return rates_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[SourceRate] | None | Unset, data)

        rates = _parse_rates(d.pop("rates", UNSET))

        step_response = cls(
            compute_micros=compute_micros,
            coordination=coordination,
            estimator=estimator,
            expected_by_step=expected_by_step,
            expected_detections=expected_detections,
            horizon=horizon,
            min_separation=min_separation,
            objective=objective,
            plans=plans,
            scenario=scenario,
            separation_violations=separation_violations,
            step=step,
            bound=bound,
            joint=joint,
            rates=rates,
        )

        step_response.additional_properties = d
        return step_response

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
