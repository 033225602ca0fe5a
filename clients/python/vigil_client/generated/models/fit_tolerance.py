from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from typing import cast


T = TypeVar("T", bound="FitTolerance")


@_attrs_define
class FitTolerance:
    """Tolerances of a fit, for trackers whose positions and velocities are
    noisy. Each is optional; the defaults accept exact data.

        Attributes:
            look (float | None | Unset): How far, zone units, a detection may lie outside every field of view
                of its step; default 10⁻⁶ × the zone's larger side.
            speed (float | None | Unset): How far a detection's speed may differ from a target class's speed,
                relative to it; default 10⁻⁶.
            traceback (float | None | Unset): How far, zone units, a source may lie from a detection's track
                traced back (and the track run outside the source's cone or past
                a building's edge) and still explain it; default 10⁻⁶ × the zone's
                larger side.
    """

    look: float | None | Unset = UNSET
    speed: float | None | Unset = UNSET
    traceback: float | None | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        look: float | None | Unset
        if isinstance(self.look, Unset):
            look = UNSET
        else:
            look = self.look

        speed: float | None | Unset
        if isinstance(self.speed, Unset):
            speed = UNSET
        else:
            speed = self.speed

        traceback: float | None | Unset
        if isinstance(self.traceback, Unset):
            traceback = UNSET
        else:
            traceback = self.traceback

        field_dict: dict[str, Any] = {}

        field_dict.update({})
        if look is not UNSET:
            field_dict["look"] = look
        if speed is not UNSET:
            field_dict["speed"] = speed
        if traceback is not UNSET:
            field_dict["traceback"] = traceback

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)

        def _parse_look(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        look = _parse_look(d.pop("look", UNSET))

        def _parse_speed(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        speed = _parse_speed(d.pop("speed", UNSET))

        def _parse_traceback(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        traceback = _parse_traceback(d.pop("traceback", UNSET))

        fit_tolerance = cls(
            look=look,
            speed=speed,
            traceback=traceback,
        )

        return fit_tolerance
