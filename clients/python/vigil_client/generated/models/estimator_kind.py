from enum import Enum


class EstimatorKind(str, Enum):
    EXACT = "exact"
    PAPER = "paper"

    def __str__(self) -> str:
        return str(self.value)
