from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define
from attrs import field as _attrs_field


if TYPE_CHECKING:
    from ..models.session_settings import SessionSettings
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
    """

    history_held: int
    history_steps: int
    id: str
    memory_bytes: int
    scenario: str
    settings: SessionSettings
    step: int
    tracks: list[Track]
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

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.session_settings import SessionSettings  # noqa: PLC0415
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

        session_info = cls(
            history_held=history_held,
            history_steps=history_steps,
            id=id,
            memory_bytes=memory_bytes,
            scenario=scenario,
            settings=settings,
            step=step,
            tracks=tracks,
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
