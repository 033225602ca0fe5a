from enum import Enum


class FovSpecType1Shape(str, Enum):
    CIRCLE = "circle"

    def __str__(self) -> str:
        return str(self.value)
