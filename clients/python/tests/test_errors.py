"""Every class of error the server answers with arrives as one `VigilError`."""

from __future__ import annotations

import pytest

from conftest import API_KEY, running_server
from vigil_client import Vigil, VigilError

SENSOR = {"id": "a", "x": 55, "y": 55}


def refusal(call) -> VigilError:
    with pytest.raises(VigilError) as caught:
        call()
    error = caught.value
    # The problem+json fields, as the server sent them.
    assert error.problem == {"type": error.type, "title": error.title, "status": error.status, "detail": error.detail}
    assert error.type.startswith("https://vigil.dev/problems/")
    return error


def test_400_a_misspelt_field_is_named_not_dropped(vigil_url: str) -> None:
    with Vigil(vigil_url) as vigil:
        error = refusal(lambda: vigil.plan("paper-v10", {"sensors": [SENSOR], "horizn": 2}))
    assert error.status == 400 and "horizn" in error.detail


def test_404_unknown_scenario_and_session(vigil_url: str) -> None:
    with Vigil(vigil_url) as vigil:
        assert refusal(lambda: vigil.plan("no-such", {"sensors": [SENSOR]})).status == 404
        session = vigil.session("paper-v10")
        session.delete()
        assert refusal(lambda: session.step({"sensors": [SENSOR]})).type.endswith("session-not-found")


def test_409_a_built_in_is_not_deleted(vigil_url: str) -> None:
    with Vigil(vigil_url) as vigil:
        assert refusal(lambda: vigil.delete_scenario("paper-v10")).status == 409


def test_413_a_body_past_the_limit(vigil_url: str) -> None:
    with Vigil(vigil_url) as vigil:
        error = refusal(lambda: vigil.plan("paper-v10", {"sensors": [SENSOR], "targets": [], "pad": "x" * (5 << 20)}))
    assert error.status == 413


def test_422_names_the_field(vigil_url: str) -> None:
    with Vigil(vigil_url) as vigil:
        error = refusal(lambda: vigil.plan("paper-v10", {"sensors": [{"id": "a", "x": -55, "y": 55}]}))
    assert error.status == 422 and error.detail.startswith("sensors[0]")


def test_401_without_or_with_a_wrong_key(strict_url: str) -> None:
    for key in (None, "wrong"):
        with Vigil(strict_url, api_key=key) as vigil:
            assert refusal(vigil.list_scenarios).status == 401
    with Vigil(strict_url, api_key=API_KEY) as vigil:
        assert vigil.list_scenarios().scenarios


def test_504_past_the_servers_time_limit() -> None:
    # One millisecond is less than any joint plan on site-fleet takes.
    with running_server("--request-timeout-ms", "1") as url, Vigil(url) as vigil:
        sensors = [{"id": i, "x": 15 + 30 * i, "y": 15} for i in range(10)]
        request = {"sensors": sensors, "coordination": "joint", "budget_ms": 1000}
        error = refusal(lambda: vigil.plan("site-fleet", request))
    assert error.status == 504


def test_a_body_that_is_not_problem_json_still_gives_the_status() -> None:
    error = VigilError.from_response(502, b"<html>bad gateway</html>", {})
    assert (error.status, error.title, error.type) == (502, "HTTP error", "about:blank")
    assert error.detail == "<html>bad gateway</html>"
    assert error.retry_after is None
