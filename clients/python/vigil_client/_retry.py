"""Waiting where the server says when: `503 Service Unavailable` with `Retry-After`.

Vigil answers 503 with `Retry-After` when it sheds load, while a scenario is
still being precomputed, and when the precomputation queue is full. The
transports here resend such a request after the delay the server gives, as
long as the total time spent waiting stays within the caller's bound. Any
other answer, and a 503 whose delay would overrun the bound, is returned as
it is. Request bodies are bytes, so a request can be sent again unchanged.
"""

from __future__ import annotations

import asyncio
import email.utils
import time
from collections.abc import Awaitable, Callable, Mapping
from datetime import datetime, timezone

import httpx

#: Seconds a client waits in total on `Retry-After` before it gives up (by default).
DEFAULT_MAX_RETRY_WAIT = 30.0


def retry_after(status: int, headers: Mapping[str, str]) -> float | None:
    """Seconds to wait before resending, when an answer is a 503 that says.

    `Retry-After` is either a number of seconds or an HTTP date (RFC 9110,
    10.2.3). Returns None for any other status, a missing header or one that
    does not parse.
    """
    if status != 503:
        return None
    value = headers.get("retry-after")
    if value is None:
        return None
    value = value.strip()
    if value.isdigit():
        return float(value)
    try:
        when = email.utils.parsedate_to_datetime(value)
    except (TypeError, ValueError):
        return None
    if when.tzinfo is None:
        when = when.replace(tzinfo=timezone.utc)
    return max(0.0, (when - datetime.now(timezone.utc)).total_seconds())


class RetryTransport(httpx.BaseTransport):
    """A transport that resends on 503 with `Retry-After`, waiting at most `max_wait` s in all.

    `on_retry(delay, response)`, if given, is called before each wait.
    """

    def __init__(
        self,
        inner: httpx.BaseTransport | None = None,
        *,
        max_wait: float = DEFAULT_MAX_RETRY_WAIT,
        on_retry: Callable[[float, httpx.Response], None] | None = None,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        if not max_wait >= 0:
            raise ValueError(f"max_wait must be at least 0 seconds, not {max_wait!r}")
        self._inner = inner if inner is not None else httpx.HTTPTransport()
        self._max_wait = max_wait
        self._on_retry = on_retry
        self._sleep = sleep

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        waited = 0.0
        while True:
            response = self._inner.handle_request(request)
            delay = retry_after(response.status_code, response.headers)
            if delay is None or waited + delay > self._max_wait:
                return response
            response.read()
            response.close()
            if self._on_retry is not None:
                self._on_retry(delay, response)
            self._sleep(delay)
            waited += delay

    def close(self) -> None:
        self._inner.close()


class AsyncRetryTransport(httpx.AsyncBaseTransport):
    """The asynchronous twin of `RetryTransport`: it waits with `asyncio.sleep`."""

    def __init__(
        self,
        inner: httpx.AsyncBaseTransport | None = None,
        *,
        max_wait: float = DEFAULT_MAX_RETRY_WAIT,
        on_retry: Callable[[float, httpx.Response], None] | None = None,
        sleep: Callable[[float], Awaitable[None]] = asyncio.sleep,
    ) -> None:
        if not max_wait >= 0:
            raise ValueError(f"max_wait must be at least 0 seconds, not {max_wait!r}")
        self._inner = inner if inner is not None else httpx.AsyncHTTPTransport()
        self._max_wait = max_wait
        self._on_retry = on_retry
        self._sleep = sleep

    async def handle_async_request(self, request: httpx.Request) -> httpx.Response:
        waited = 0.0
        while True:
            response = await self._inner.handle_async_request(request)
            delay = retry_after(response.status_code, response.headers)
            if delay is None or waited + delay > self._max_wait:
                return response
            await response.aread()
            await response.aclose()
            if self._on_retry is not None:
                self._on_retry(delay, response)
            await self._sleep(delay)
            waited += delay

    async def aclose(self) -> None:
        await self._inner.aclose()
