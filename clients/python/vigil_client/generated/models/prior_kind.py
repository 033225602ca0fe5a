from enum import Enum


class PriorKind(str, Enum):
    FLAT = "flat"
    SCENARIO = "scenario"

    def __str__(self) -> str:
        return str(self.value)
