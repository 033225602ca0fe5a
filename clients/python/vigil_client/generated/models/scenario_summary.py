from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar, TYPE_CHECKING

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from ..models.scenario_status import ScenarioStatus
from typing import cast

if TYPE_CHECKING:
    from ..models.grid import Grid
    from ..models.scenario_spec import ScenarioSpec
    from ..models.summary_stats import SummaryStats


T = TypeVar("T", bound="ScenarioSummary")


@_attrs_define
class ScenarioSummary:
    """A registered scenario, as `GET /v1/scenarios/{id}` returns it.

    Attributes:
        grid (Grid): Size of a scenario's lattice.
        id (str): Scenario id.
        predicted_precompute_ms (float): The precomputation's predicted wall time on this server,
            milliseconds (above `--sync-precompute-ms` it runs as a job).
        progress (float): Share of the precomputation done, 0..1 (1 when ready).
        spec (ScenarioSpec): A scenario as clients send it.
        status (ScenarioStatus): Where a scenario is in its lifecycle.
        eta_s (float | None | Unset): Estimated seconds until it is ready; only while pending.
        queue_position (int | None | Unset): Place in the precomputation queue (1 = next); only while queued.
        summary (None | SummaryStats | Unset):
    """

    grid: Grid
    id: str
    predicted_precompute_ms: float
    progress: float
    spec: ScenarioSpec
    status: ScenarioStatus
    eta_s: float | None | Unset = UNSET
    queue_position: int | None | Unset = UNSET
    summary: None | SummaryStats | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        from ..models.summary_stats import SummaryStats  # noqa: PLC0415

        grid = self.grid.to_dict()

        id = self.id

        predicted_precompute_ms = self.predicted_precompute_ms

        progress = self.progress

        spec = self.spec.to_dict()

        status = self.status.value

        eta_s: float | None | Unset
        if isinstance(self.eta_s, Unset):
            eta_s = UNSET
        else:
            eta_s = self.eta_s

        queue_position: int | None | Unset
        if isinstance(self.queue_position, Unset):
            queue_position = UNSET
        else:
            queue_position = self.queue_position

        summary: dict[str, Any] | None | Unset
        if isinstance(self.summary, Unset):
            summary = UNSET
        elif isinstance(self.summary, SummaryStats):
            summary = self.summary.to_dict()
        else:
            summary = self.summary

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "grid": grid,
                "id": id,
                "predicted_precompute_ms": predicted_precompute_ms,
                "progress": progress,
                "spec": spec,
                "status": status,
            }
        )
        if eta_s is not UNSET:
            field_dict["eta_s"] = eta_s
        if queue_position is not UNSET:
            field_dict["queue_position"] = queue_position
        if summary is not UNSET:
            field_dict["summary"] = summary

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        from ..models.grid import Grid  # noqa: PLC0415
        from ..models.scenario_spec import ScenarioSpec  # noqa: PLC0415
        from ..models.summary_stats import SummaryStats  # noqa: PLC0415

        d = dict(src_dict)
        grid = Grid.from_dict(d.pop("grid"))

        id = d.pop("id")

        predicted_precompute_ms = d.pop("predicted_precompute_ms")

        progress = d.pop("progress")

        spec = ScenarioSpec.from_dict(d.pop("spec"))

        status = ScenarioStatus(d.pop("status"))

        def _parse_eta_s(data: object) -> float | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(float | None | Unset, data)

        eta_s = _parse_eta_s(d.pop("eta_s", UNSET))

        def _parse_queue_position(data: object) -> int | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            return cast(int | None | Unset, data)

        queue_position = _parse_queue_position(d.pop("queue_position", UNSET))

        def _parse_summary(data: object) -> None | SummaryStats | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, dict):
                    raise TypeError()
                summary_type_0 = SummaryStats.from_dict(data)

                return summary_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(None | SummaryStats | Unset, data)

        summary = _parse_summary(d.pop("summary", UNSET))

        scenario_summary = cls(
            grid=grid,
            id=id,
            predicted_precompute_ms=predicted_precompute_ms,
            progress=progress,
            spec=spec,
            status=status,
            eta_s=eta_s,
            queue_position=queue_position,
            summary=summary,
        )

        scenario_summary.additional_properties = d
        return scenario_summary

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
