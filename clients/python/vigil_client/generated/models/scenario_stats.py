from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast

if TYPE_CHECKING:
    from ..models.obstacle_spec import ObstacleSpec


T = TypeVar("T", bound="ScenarioStats")


@_attrs_define
class ScenarioStats:
    """Per-cell statistics of a scenario, each array row-major (`row·cols + col`).

    Attributes:
        cell_size (float): Side of a cell.
        cols (int): Columns.
        d_hat (list[float]): Stationary expected number of targets in each cell's field of view.
        escape_time (list[float]): Expected stay of an entering target in each cell's field of view.
        lambda_hat (list[float]): Expected rate of target entry into each cell's field of view.
        rows (int): Rows.
        type_ (str): The sensor type whose field of view they are for.
        obstacles (list[ObstacleSpec] | Unset): The scenario's obstacles (absent when it has none), to draw over
            the statistics: with obstacles, each cell's statistics count only
            the part of its field of view it sees (all of it for an elevated
            type) and the targets no building has stopped.
    """

    cell_size: float
    cols: int
    d_hat: list[float]
    escape_time: list[float]
    lambda_hat: list[float]
    rows: int
    type_: str
    obstacles: list[ObstacleSpec] | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        cell_size = self.cell_size

        cols = self.cols

        d_hat = self.d_hat

        escape_time = self.escape_time

        lambda_hat = self.lambda_hat

        rows = self.rows

        type_ = self.type_

        obstacles: list[dict[str, Any]] | Unset = UNSET
        if not isinstance(self.obstacles, Unset):
            obstacles = []
            for obstacles_item_data in self.obstacles:
                obstacles_item = obstacles_item_data.to_dict()
                obstacles.append(obstacles_item)

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "cell_size": cell_size,
                "cols": cols,
                "d_hat": d_hat,
                "escape_time": escape_time,
                "lambda_hat": lambda_hat,
                "rows": rows,
                "type": type_,
            }
        )
        if obstacles is not UNSET:
            field_dict["obstacles"] = obstacles

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.obstacle_spec import ObstacleSpec  # noqa: PLC0415

        d = dict(src_dict)
        cell_size = d.pop("cell_size")

        cols = d.pop("cols")

        d_hat = cast(list[float], d.pop("d_hat"))

        escape_time = cast(list[float], d.pop("escape_time"))

        lambda_hat = cast(list[float], d.pop("lambda_hat"))

        rows = d.pop("rows")

        type_ = d.pop("type")

        _obstacles = d.pop("obstacles", UNSET)
        obstacles: list[ObstacleSpec] | Unset = UNSET
        if _obstacles is not UNSET:
            obstacles = []
            for obstacles_item_data in _obstacles:
                obstacles_item = ObstacleSpec.from_dict(obstacles_item_data)

                obstacles.append(obstacles_item)

        scenario_stats = cls(
            cell_size=cell_size,
            cols=cols,
            d_hat=d_hat,
            escape_time=escape_time,
            lambda_hat=lambda_hat,
            rows=rows,
            type_=type_,
            obstacles=obstacles,
        )

        scenario_stats.additional_properties = d
        return scenario_stats

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
