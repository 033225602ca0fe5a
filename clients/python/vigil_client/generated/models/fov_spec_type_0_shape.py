from enum import Enum


class FovSpecType0Shape(str, Enum):
    SQUARE = "square"

    def __str__(self) -> str:
        return str(self.value)
