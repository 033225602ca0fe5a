from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
    from ..models.source_rate import SourceRate
    from ..models.unexplained import Unexplained


T = TypeVar("T", bound="FitResponse")


@_attrs_define
class FitResponse:
    """Response of `POST /v1/scenarios/{id}/fit`.

    Attributes:
        scenario (str): The scenario fitted.
        sources (list[SourceRate]): Each source's fitted rate, in the scenario's order.
        steps (int): Steps in the window.
        unexplained (list[Unexplained]): Detected targets that no source explains.
        id (None | str | Unset): With `register`: the id of the scenario registered with the fitted
            rates.
    """

    scenario: str
    sources: list[SourceRate]
    steps: int
    unexplained: list[Unexplained]
    id: None | str | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        scenario = self.scenario

        sources = []
        for sources_item_data in self.sources:
            sources_item = sources_item_data.to_dict()
            sources.append(sources_item)

        steps = self.steps

        unexplained = []
        for unexplained_item_data in self.unexplained:
            unexplained_item = unexplained_item_data.to_dict()
            unexplained.append(unexplained_item)

        id: None | str | Unset
        if isinstance(self.id, Unset):
            id = UNSET
        else:
            id = self.id

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "scenario": scenario,
                "sources": sources,
                "steps": steps,
                "unexplained": unexplained,
            }
        )
        if id is not UNSET:
            field_dict["id"] = id

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.source_rate import SourceRate  # noqa: PLC0415
        from ..models.unexplained import Unexplained  # noqa: PLC0415

        d = dict(src_dict)
        scenario = d.pop("scenario")

        sources = []
        _sources = d.pop("sources")
        for sources_item_data in _sources:
            sources_item = SourceRate.from_dict(sources_item_data)

            sources.append(sources_item)

        steps = d.pop("steps")

        unexplained = []
        _unexplained = d.pop("unexplained")
        for unexplained_item_data in _unexplained:
            unexplained_item = Unexplained.from_dict(unexplained_item_data)

            unexplained.append(unexplained_item)

        def _parse_id(data: object) -> None | str | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(None | str | Unset, data)

        id = _parse_id(d.pop("id", UNSET))

        fit_response = cls(
            scenario=scenario,
            sources=sources,
            steps=steps,
            unexplained=unexplained,
            id=id,
        )

        fit_response.additional_properties = d
        return fit_response

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
