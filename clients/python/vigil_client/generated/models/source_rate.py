from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

from attrs import define as _attrs_define
from attrs import field as _attrs_field

from ..types import UNSET, Unset

from typing import cast


T = TypeVar("T", bound="SourceRate")


@_attrs_define
class SourceRate:
    """A source's fitted rate.

    Attributes:
        detected (float): Distinct targets detected from the source (fractional when a
            detection is shared between sources).
        exposure (float): Expected distinct targets detected per unit rate (steps): the
            window's looks detect `rate × exposure` of the source's targets on
            average, counting every target in the zone during the window.
        index (int): The source's index in the scenario's `sources`.
        rate (float): Targets per step: the posterior mean (the spec's rate when the
            posterior is improper: a flat prior that no look exposed).
        interval (list[float] | None | Unset): The equal-tailed 95% credible interval `[lo, hi]` (the posterior's
            2.5% and 97.5% quantiles); `null` when the posterior is improper.
    """

    detected: float
    exposure: float
    index: int
    rate: float
    interval: list[float] | None | Unset = UNSET
    additional_properties: dict[str, Any] = _attrs_field(init=False, factory=dict)

    def to_dict(self) -> dict[str, Any]:
        detected = self.detected

        exposure = self.exposure

        index = self.index

        rate = self.rate

        interval: list[float] | None | Unset
        if isinstance(self.interval, Unset):
            interval = UNSET
        elif isinstance(self.interval, list):
            interval = self.interval

        else:
            interval = self.interval

        field_dict: dict[str, Any] = {}
        field_dict.update(self.additional_properties)
        field_dict.update(
            {
                "detected": detected,
                "exposure": exposure,
                "index": index,
                "rate": rate,
            }
        )
        if interval is not UNSET:
            field_dict["interval"] = interval

        return field_dict

    @classmethod
    def from_dict(cls: type[T], src_dict: Mapping[str, Any]) -> T:
        d = dict(src_dict)
        detected = d.pop("detected")

        exposure = d.pop("exposure")

        index = d.pop("index")

        rate = d.pop("rate")

        def _parse_interval(data: object) -> list[float] | None | Unset:
            if data is None:
                return data
            if isinstance(data, Unset):
                return data
            try:
                if not isinstance(data, list):
                    raise TypeError()
                interval_type_0 = cast(list[float], data)

                return interval_type_0
            except (TypeError, ValueError, AttributeError, KeyError):
                pass
            return cast(list[float] | None | Unset, data)

        interval = _parse_interval(d.pop("interval", UNSET))

        source_rate = cls(
            detected=detected,
            exposure=exposure,
            index=index,
            rate=rate,
            interval=interval,
        )

        source_rate.additional_properties = d
        return source_rate

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
