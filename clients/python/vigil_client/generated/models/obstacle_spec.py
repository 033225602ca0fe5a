from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define

from ..types import UNSET, Unset

from ..models.obstacle_kind_name import ObstacleKindName
from typing import cast


T = TypeVar("T", bound="ObstacleSpec")


@_attrs_define
class ObstacleSpec:
    """An obstacle as clients send it: a convex polygon and what it blocks.

    Attributes:
        polygon (list[list[float]]): The outline: 3 to 32 vertices `[x, y]` of a convex polygon, in zone
            coordinates, in either order around it, no vertex repeated and no
            three consecutive ones collinear, each coordinate within ±1e9. It
            may cross the zone's edge but not lie wholly outside it.
        kind (None | ObstacleKindName | Unset):
    """

    polygon: list[list[float]]
    kind: None | ObstacleKindName | Unset = UNSET

    def to_dict(self) -> dict[str, Any]:
        polygon = []
        for polygon_item_data in self.polygon:
            polygon_item = polygon_item_data

            polygon.append(polygon_item)

        kind: None | str | Unset
        if isinstance(self.kind, Unset):
            kind = UNSET
        elif isinstance(self.kind, ObstacleKindName):
            kind = self.kind.value
        else:
            kind = self.kind

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "polygon": polygon,
            }
        )
        if kind is not UNSET:
            field_dict["kind"] = kind

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        polygon = []
        _polygon = d.pop("polygon")
        for polygon_item_data in _polygon:
            polygon_item = cast(list[float], polygon_item_data)

            polygon.append(polygon_item)

        def _parse_kind(data: object) -> None | ObstacleKindName | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, str):
                    raise TypeError()
                kind_type_0 = ObstacleKindName(data)

                return kind_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | ObstacleKindName | Unset, data)

        kind = _parse_kind(d.pop("kind", UNSET))

        obstacle_spec = cls(
            polygon=polygon,
            kind=kind,
        )

        return obstacle_spec
