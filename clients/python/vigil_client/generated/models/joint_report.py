from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define
from attrs import field as _attrs_field


from ..models.joint_stop import JointStop


T = TypeVar("T", bound="JointReport")


@_attrs_define
class JointReport:
    """What `joint` did.

    Attributes:
        micros (int): Time from the plan's start to the end of the last round,
            microseconds.
        rounds (int): Rounds of tightening and restarting run after `Iterated`.
        stopped (JointStop): Why `joint` stopped.
    """

    micros: int
    rounds: int
    stopped: JointStop
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        micros = self.micros

        rounds = self.rounds

        stopped = self.stopped.value

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "micros": micros,
                "rounds": rounds,
                "stopped": stopped,
            }
        )

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        micros = d.pop("micros")

        rounds = d.pop("rounds")

        stopped = JointStop(d.pop("stopped"))

        joint_report = cls(
            micros=micros,
            rounds=rounds,
            stopped=stopped,
        )

        joint_report.additional_properties = d
        return joint_report

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
