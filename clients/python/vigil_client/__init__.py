"""A typed client for Vigil, the planning service for mobile surveillance sensors.

    from vigil_client import Vigil

    with Vigil("http://127.0.0.1:8080") as vigil:
        plan = vigil.plan("paper-v10", {"sensors": [{"id": "a", "x": 150, "y": 150}]})
        print([(cell.x, cell.y) for cell in plan.plans[0].path])

`Vigil` (and `AsyncVigil`) have a method per operation; requests are the
models in `vigil_client.models` or plain mappings of the same JSON, answers
are models. Failures raise `VigilError`; 503 answers with `Retry-After` are
waited out first, within `max_retry_wait` seconds. `vigil_client.generated`
is the code openapi-python-client generates from the server's OpenAPI
document; everything else here is written by hand on top of it.
"""

from . import models
from ._client import DEFAULT_TIMEOUT, DEFAULT_URL, AsyncSession, AsyncVigil, Session, Vigil
from ._errors import VigilError
from ._retry import DEFAULT_MAX_RETRY_WAIT, AsyncRetryTransport, RetryTransport, retry_after

__all__ = [
    "DEFAULT_MAX_RETRY_WAIT",
    "DEFAULT_TIMEOUT",
    "DEFAULT_URL",
    "AsyncRetryTransport",
    "AsyncSession",
    "AsyncVigil",
    "RetryTransport",
    "Session",
    "Vigil",
    "VigilError",
    "models",
    "retry_after",
]
