from enum import Enum


class Objective(str, Enum):
    DETECTIONS = "detections"
    FIRST_DETECTIONS = "first_detections"

    def __str__(self) -> str:
        return str(self.value)
