from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from ..models.prior_kind import PriorKind
from typing import cast

if TYPE_CHECKING:
    from ..models.fit_step import FitStep
    from ..models.fit_tolerance import FitTolerance


T = TypeVar("T", bound="FitRequest")


@_attrs_define
class FitRequest:
    """Body of `POST /v1/scenarios/{id}/fit`.

    Attributes:
        steps (list[FitStep]): Consecutive steps, oldest first (1 to 500).
        prior (None | PriorKind | Unset):
        register (bool | None | Unset): Register the fitted spec (the same spec with the fitted rates) as a
            new scenario; `false` by default.
        tolerance (FitTolerance | None | Unset):
    """

    steps: list[FitStep]
    prior: None | PriorKind | Unset = UNSET
    register: bool | None | Unset = UNSET
    tolerance: FitTolerance | None | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        from ..models.fit_tolerance import FitTolerance  # noqa: PLC0415

        steps = []
        for steps_item_data in self.steps:
            steps_item = steps_item_data.to_dict()
            steps.append(steps_item)

        prior: None | str | Unset
        if isinstance(self.prior, Unset):
            prior = UNSET
        elif isinstance(self.prior, PriorKind):
            prior = self.prior.value
        else:
            prior = self.prior

        register: bool | None | Unset
        if isinstance(self.register, Unset):
            register = UNSET
        else:
            register = self.register

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
                "steps": steps,
            }
        )
        if prior is not UNSET:
            field_dict["prior"] = prior
        if register is not UNSET:
            field_dict["register"] = register
        if tolerance is not UNSET:
            field_dict["tolerance"] = tolerance

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.fit_step import FitStep  # noqa: PLC0415
        from ..models.fit_tolerance import FitTolerance  # noqa: PLC0415

        d = dict(src_dict)
        steps = []
        _steps = d.pop("steps")
        for steps_item_data in _steps:
            steps_item = FitStep.from_dict(steps_item_data)

            steps.append(steps_item)

        def _parse_prior(data: object) -> None | PriorKind | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, str):
                    raise TypeError()
                prior_type_0 = PriorKind(data)

                return prior_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | PriorKind | Unset, data)

        prior = _parse_prior(d.pop("prior", UNSET))

        def _parse_register(data: object) -> bool | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(bool | None | Unset, data)

        register = _parse_register(d.pop("register", UNSET))

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

        fit_request = cls(
            steps=steps,
            prior=prior,
            register=register,
            tolerance=tolerance,
        )

        return fit_request
