from enum import Enum


class Observed(str, Enum):
    SENSORS = "sensors"
    ZONE = "zone"

    def __str__(self) -> str:
        return str(self.value)
