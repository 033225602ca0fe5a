from enum import Enum


class ObstacleKindName(str, Enum):
    BUILDING = "building"
    SCREEN = "screen"

    def __str__(self) -> str:
        return str(self.value)
