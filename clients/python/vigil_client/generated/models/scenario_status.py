from enum import Enum


class ScenarioStatus(str, Enum):
    PRECOMPUTING = "precomputing"
    QUEUED = "queued"
    READY = "ready"
    STORED = "stored"

    def __str__(self) -> str:
        return str(self.value)
