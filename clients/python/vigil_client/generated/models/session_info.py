from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
    from ..models.session_settings import SessionSettings
    from ..models.source_rate import SourceRate
    from ..models.track import Track


T = TypeVar("T", bound="SessionInfo")


@_attrs_define
class SessionInfo:
    """A session, as `POST /v1/sessions` and `GET /v1/sessions/{id}` return it.

    Attributes:
        history_held (int): Steps of history held now.
        history_steps (int): Steps of history kept.
        id (str): Session id.
        memory_bytes (int): Approximate memory it holds, bytes (the scenario's statistics,
            shared, aside).
        scenario (str): Its scenario's id.
        settings (SessionSettings): A session's defaults for its steps; a step may override each but
            `history_steps`.
        step (int): Steps made so far: the number of the next step.
        tracks (list[Track]): The targets it follows after the last step.
        rates (list[SourceRate] | None | Unset): With `learn_rates`: each source's rate learnt so far.
    """

    history_held: int
    history_steps: int
    id: str
    memory_bytes: int
    scenario: str
    settings: SessionSettings
    step: int
    tracks: list[Track]
    rates: list[SourceRate] | None | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        history_held = self.history_held

        history_steps = self.history_steps

        id = self.id

        memory_bytes = self.memory_bytes

        scenario = self.scenario

        settings = self.settings.to_dict()

        step = self.step

        tracks = []
        for tracks_item_data in self.tracks:
            tracks_item = tracks_item_data.to_dict()
            tracks.append(tracks_item)

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
                "history_held": history_held,
                "history_steps": history_steps,
                "id": id,
                "memory_bytes": memory_bytes,
                "scenario": scenario,
                "settings": settings,
                "step": step,
                "tracks": tracks,
            }
        )
        if rates is not UNSET:
            field_dict["rates"] = rates

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.session_settings import SessionSettings  # noqa: PLC0415
        from ..models.source_rate import SourceRate  # noqa: PLC0415
        from ..models.track import Track  # noqa: PLC0415

        d = dict(src_dict)
        history_held = d.pop("history_held")

        history_steps = d.pop("history_steps")

        id = d.pop("id")

        memory_bytes = d.pop("memory_bytes")

        scenario = d.pop("scenario")

        settings = SessionSettings.from_dict(d.pop("settings"))

        step = d.pop("step")

        tracks = []
        _tracks = d.pop("tracks")
        for tracks_item_data in _tracks:
            tracks_item = Track.from_dict(tracks_item_data)

            tracks.append(tracks_item)

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

        session_info = cls(
            history_held=history_held,
            history_steps=history_steps,
            id=id,
            memory_bytes=memory_bytes,
            scenario=scenario,
            settings=settings,
            step=step,
            tracks=tracks,
            rates=rates,
        )

        session_info.additional_properties = d
        return session_info

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
