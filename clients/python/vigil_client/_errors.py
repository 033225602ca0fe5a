"""One exception for every answer that is not a success."""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

from ._retry import retry_after

_STATUS_TITLES = {400: "Bad Request", 401: "Unauthorized", 404: "Not Found", 503: "Service Unavailable"}


class VigilError(Exception):
    """Vigil refused or failed a request: its problem+json (RFC 9457) fields.

    Attributes:
        type: the problem's type URI (`about:blank` when the body had none).
        title: a short summary of the kind of problem.
        status: the HTTP status code.
        detail: what went wrong with this request (for a 422, it names the field).
        retry_after: for a 503, the seconds the server asked to wait, else None.
        problem: the whole problem object as the server sent it (empty if the
            body was not JSON).
    """

    def __init__(
        self,
        status: int,
        title: str,
        detail: str,
        type: str = "about:blank",
        *,
        retry_after: float | None = None,
        problem: Mapping[str, Any] | None = None,
    ) -> None:
        super().__init__(f"{status} {title}: {detail}")
        self.type = type
        self.title = title
        self.status = status
        self.detail = detail
        self.retry_after = retry_after
        self.problem = dict(problem or {})

    @classmethod
    def from_response(cls, status: int, content: bytes, headers: Mapping[str, str]) -> VigilError:
        """The error an answer stands for; a body that is not problem+json still gives one."""
        try:
            problem = json.loads(content)
        except ValueError:
            problem = None
        if not isinstance(problem, dict):
            text = content.decode("utf-8", "replace").strip()
            problem = {}
        else:
            text = ""
        title = problem.get("title")
        detail = problem.get("detail")
        kind = problem.get("type")
        return cls(
            status,
            title if isinstance(title, str) else _STATUS_TITLES.get(status, "HTTP error"),
            detail if isinstance(detail, str) else text,
            kind if isinstance(kind, str) else "about:blank",
            retry_after=retry_after(status, headers),
            problem=problem,
        )
