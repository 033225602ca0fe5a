"""Waiting out 503 with Retry-After: against the server, and the bound on the wait."""

from __future__ import annotations

import email.utils
import time

import httpx
import pytest

from conftest import API_KEY
from vigil_client import RetryTransport, Vigil, VigilError, retry_after

#: A scenario of 2.56 M cells: its precomputation keeps the one precompute job busy for a while.
BLOCKER = {
    "name": "pytest blocker",
    "zone": {"width": 4000, "height": 4000},
    "cell_size": 2.5,
    "fov": {"shape": "square", "half_width": 15},
    "target_speed": 10,
    "sources": [{"x": -1, "y": 2000, "rate": 0.5}, {"x": 2000, "y": 4001, "rate": 0.3}],
}


def queued_scenario(vigil: Vigil, name: str) -> str:
    """Registers the blocker, then a small scenario queued behind it; returns the small one's id."""
    vigil.create_scenario({**BLOCKER, "name": f"{name} blocker"})
    small = {**BLOCKER, "name": name, "zone": {"width": 200, "height": 100}, "cell_size": 10}
    small["sources"] = [{"x": -1, "y": 50, "rate": 0.5}]
    created = vigil.create_scenario(small)
    assert created.status != "ready"
    return created.id


def test_a_plan_waits_until_its_scenario_is_ready(strict_url: str) -> None:
    waits: list[float] = []
    with Vigil(strict_url, api_key=API_KEY, max_retry_wait=300, on_retry=lambda d, r: waits.append(d)) as vigil:
        scenario = queued_scenario(vigil, "pytest waits")
        plan = vigil.plan(scenario, {"sensors": [{"id": "a", "x": 55, "y": 55}]})
    assert waits and all(w >= 1 for w in waits)
    assert len(plan.plans[0].path) == 3


def test_the_wait_is_bounded_by_the_caller(strict_url: str) -> None:
    with Vigil(strict_url, api_key=API_KEY, max_retry_wait=0) as vigil:
        scenario = queued_scenario(vigil, "pytest gives up")
        started = time.monotonic()
        with pytest.raises(VigilError) as caught:
            vigil.plan(scenario, {"sensors": [{"id": "a", "x": 55, "y": 55}]})
    assert time.monotonic() - started < 1
    error = caught.value
    assert error.status == 503 and error.type.endswith("scenario-not-ready")
    assert error.retry_after is not None and error.retry_after >= 1


def test_retry_after_reads_seconds_and_dates() -> None:
    assert retry_after(503, {"retry-after": "7"}) == 7
    later = email.utils.format_datetime(email.utils.localtime().replace(microsecond=0), usegmt=False)
    assert retry_after(503, {"retry-after": later}) == pytest.approx(0, abs=2)
    assert retry_after(503, {"retry-after": "soon"}) is None
    assert retry_after(503, {}) is None
    assert retry_after(429, {"retry-after": "7"}) is None


def test_the_transport_stops_when_the_next_wait_would_overrun() -> None:
    answers = iter([503, 503, 503, 200])
    sent, slept = [], []

    def handler(request: httpx.Request) -> httpx.Response:
        sent.append(request.content)
        return httpx.Response(next(answers), headers={"retry-after": "2"})

    transport = RetryTransport(httpx.MockTransport(handler), max_wait=5, sleep=slept.append)
    with httpx.Client(transport=transport) as client:
        response = client.post("http://vigil.test/v1/plan", json={"sensors": []})
    # Waits of 2 s and 2 s fit in 5 s; a third would not, so the third 503 is returned.
    assert response.status_code == 503
    assert slept == [2, 2]
    assert sent == [b'{"sensors":[]}'] * 3


def test_the_async_transport_waits_the_same_way() -> None:
    import asyncio

    from vigil_client import AsyncRetryTransport

    answers = iter([503, 503, 200])
    slept: list[float] = []

    def handler(request: httpx.Request) -> httpx.Response:
        return httpx.Response(next(answers), headers={"retry-after": "1"})

    async def sleep(delay: float) -> None:
        slept.append(delay)

    async def run() -> int:
        transport = AsyncRetryTransport(httpx.MockTransport(handler), max_wait=5, sleep=sleep)
        async with httpx.AsyncClient(transport=transport) as client:
            return (await client.get("http://vigil.test/v1/scenarios")).status_code

    assert asyncio.run(run()) == 200
    assert slept == [1, 1]


def test_a_negative_bound_is_refused() -> None:
    with pytest.raises(ValueError, match="max_wait"):
        Vigil(max_retry_wait=-1)
