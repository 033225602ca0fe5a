from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
    from ..models.fov_spec_type_0 import FovSpecType0
    from ..models.fov_spec_type_1 import FovSpecType1


T = TypeVar("T", bound="SensorTypeSpec")


@_attrs_define
class SensorTypeSpec:
    """A sensor type as clients send it.

    Attributes:
        fov (FovSpecType0 | FovSpecType1): Field of view of every sensor, tagged by `shape`.
        elevated (bool | None | Unset): True for a type that sees over every obstacle and may fly over
            buildings (a drone); false by default (a ground sensor, whose sight
            lines obstacles block and which never stands on a building's cell).
        p_detect (float | None | Unset): Probability of detecting a target inside the field of view at a
            step, in (0, 1]; 1 by default.
        speed (int | None | Unset): Cells (king moves) per step, 1..=3; 1 by default.
    """

    fov: FovSpecType0 | FovSpecType1
    elevated: bool | None | Unset = UNSET
    p_detect: float | None | Unset = UNSET
    speed: int | None | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        from ..models.fov_spec_type_0 import FovSpecType0  # noqa: PLC0415

        fov: dict[str, Any]
        if isinstance(self.fov, FovSpecType0):
            fov = self.fov.to_dict()
        else:
            fov = self.fov.to_dict()

        elevated: bool | None | Unset
        if isinstance(self.elevated, Unset):
            elevated = UNSET
        else:
            elevated = self.elevated

        p_detect: float | None | Unset
        if isinstance(self.p_detect, Unset):
            p_detect = UNSET
        else:
            p_detect = self.p_detect

        speed: int | None | Unset
        if isinstance(self.speed, Unset):
            speed = UNSET
        else:
            speed = self.speed

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "fov": fov,
            }
        )
        if elevated is not UNSET:
            field_dict["elevated"] = elevated
        if p_detect is not UNSET:
            field_dict["p_detect"] = p_detect
        if speed is not UNSET:
            field_dict["speed"] = speed

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.fov_spec_type_0 import FovSpecType0  # noqa: PLC0415
        from ..models.fov_spec_type_1 import FovSpecType1  # noqa: PLC0415

        d = dict(src_dict)

        def _parse_fov(data: object) -> FovSpecType0 | FovSpecType1:
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                componentsschemas_fov_spec_type_0 = FovSpecType0.from_dict(data)

                return componentsschemas_fov_spec_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            if not isinstance(data, dict):
                raise TypeError()
            componentsschemas_fov_spec_type_1 = FovSpecType1.from_dict(data)

            return componentsschemas_fov_spec_type_1

        fov = _parse_fov(d.pop("fov"))

        def _parse_elevated(data: object) -> bool | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(bool | None | Unset, data)

        elevated = _parse_elevated(d.pop("elevated", UNSET))

        def _parse_p_detect(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        p_detect = _parse_p_detect(d.pop("p_detect", UNSET))

        def _parse_speed(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        speed = _parse_speed(d.pop("speed", UNSET))

        sensor_type_spec = cls(
            fov=fov,
            elevated=elevated,
            p_detect=p_detect,
            speed=speed,
        )

        return sensor_type_spec
