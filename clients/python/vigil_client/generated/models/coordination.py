from enum import Enum


class Coordination(str, Enum):
    ITERATED = "iterated"
    JOINT = "joint"
    NONE = "none"
    PRIORITY = "priority"

    def __str__(self) -> str:
        return str(self.value)
