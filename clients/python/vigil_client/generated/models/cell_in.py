from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define


T = TypeVar("T", bound="CellIn")


@_attrs_define
class CellIn:
    """A cell of a path.

    Attributes:
        col (int): Column, from 0 at the west edge.
        row (int): Row, from 0 at the south edge.
    """

    col: int
    row: int

    def to_dict(self) -> dict[str, Any]:
        col = self.col

        row = self.row

        field_dict: dict[str, Any] = {}

        field_dict.update(
            {
                "col": col,
                "row": row,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        col = d.pop("col")

        row = d.pop("row")

        cell_in = cls(
            col=col,
            row=row,
        )

        return cell_in
