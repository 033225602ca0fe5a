from enum import Enum


class JointStop(str, Enum):
    BUDGET = "budget"
    GAP = "gap"
    SETTLED = "settled"

    def __str__(self) -> str:
        return str(self.value)
