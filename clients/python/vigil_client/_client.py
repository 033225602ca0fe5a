"""`Vigil` and `AsyncVigil`: the API as one method per operation, over the generated code.

Each method takes the generated model of its request, or a plain mapping of
the same JSON (sent as given), and returns the generated model of the answer. An answer that
is not a success raises `VigilError`. A 503 with `Retry-After` is waited out
and resent first, within `max_retry_wait` seconds in all (see `_retry`).
Transport failures (connection refused, timeouts) raise httpx's exceptions.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Mapping
from types import TracebackType
from typing import Any

import httpx
from typing_extensions import Self

from ._errors import VigilError
from ._retry import DEFAULT_MAX_RETRY_WAIT, AsyncRetryTransport, RetryTransport
from .generated import AuthenticatedClient, Client
from .generated.api.health import get_health
from .generated.api.planning import evaluate, evaluate_scenario, plan, plan_scenario
from .generated.api.scenarios import (
    create_scenario,
    delete_scenario,
    fit_scenario,
    get_scenario,
    get_scenario_stats,
    list_scenarios,
)
from .generated.api.sessions import create_session, delete_session, get_session, step_session
from .generated.models import (
    EvaluateBody,
    EvaluateRequestById,
    EvaluateRequestWithScenario,
    EvaluateResponse,
    FitRequest,
    FitResponse,
    Health,
    PlanRequest,
    PlanRequestById,
    PlanRequestWithScenario,
    PlanResponse,
    ScenarioList,
    ScenarioSpec,
    ScenarioStats,
    ScenarioSummary,
    SessionInfo,
    StepRequest,
    StepResponse,
)
from .generated.types import UNSET, Response

#: Where `vigil-server` listens by default.
DEFAULT_URL = "http://127.0.0.1:8080"
#: Seconds one HTTP exchange may take (by default).
DEFAULT_TIMEOUT = 30.0

Body = Mapping[str, Any]
OnRetry = Callable[[float, httpx.Response], None]


class _Json:
    """A body given as a mapping, sent exactly as given: the server judges it, so a
    misspelt field is refused with a 400 that names it rather than dropped."""

    def __init__(self, value: Body) -> None:
        self._value = value

    def to_dict(self) -> dict[str, Any]:
        return dict(self._value)


def _body(value: Any, *models: type) -> Any:
    """`value` as a request body: one of `models`, or a mapping of the same JSON."""
    if isinstance(value, models):
        return value
    if isinstance(value, Mapping):
        return _Json(value)
    names = " or ".join(m.__name__ for m in models)
    raise TypeError(f"expected {names} or a mapping, not {type(value).__name__}")


def _session_body(scenario_id: str | None, scenario: ScenarioSpec | Body | None, settings: Body) -> _Json:
    if (scenario_id is None) == (scenario is None):
        raise ValueError("give exactly one of scenario_id and scenario")
    if scenario_id is not None:
        return _Json({"scenario_id": scenario_id, **settings})
    spec = scenario.to_dict() if isinstance(scenario, ScenarioSpec) else dict(scenario)  # type: ignore[union-attr, arg-type]
    return _Json({"scenario": spec, **settings})


def _result(response: Response[Any]) -> Any:
    """The parsed answer of a success; a `VigilError` for anything else."""
    if 200 <= response.status_code < 300:
        return response.parsed
    raise VigilError.from_response(response.status_code, response.content, response.headers)


def _generated_client(
    base_url: str,
    api_key: str | None,
    timeout: float,
    transport: httpx.BaseTransport | httpx.AsyncBaseTransport,
    is_async: bool,
) -> Client:
    args: dict[str, Any] = {"transport": transport}
    kwargs: dict[str, Any] = {
        "base_url": base_url.rstrip("/"),
        "timeout": httpx.Timeout(timeout),
        "httpx_args": args,
    }
    client: Client
    if api_key is not None:
        client = AuthenticatedClient(token=api_key, **kwargs)  # type: ignore[assignment]
    else:
        client = Client(**kwargs)
    # Build only the httpx client this facade uses, with its transport.
    if is_async:
        client.get_async_httpx_client()
    else:
        client.get_httpx_client()
    return client


class Vigil:
    """A synchronous client of one Vigil server.

    Args:
        base_url: the server, `http://127.0.0.1:8080` by default.
        api_key: sent as `Authorization: Bearer …` when the server requires one.
        timeout: seconds one HTTP exchange may take.
        max_retry_wait: seconds the client may spend, per call, waiting out
            503 answers with `Retry-After` before it raises; 0 never waits.
        on_retry: called with the delay and the 503 answer before each wait.

    Use it as a context manager, or call `close()`, to release its connections.
    """

    def __init__(
        self,
        base_url: str = DEFAULT_URL,
        *,
        api_key: str | None = None,
        timeout: float = DEFAULT_TIMEOUT,
        max_retry_wait: float = DEFAULT_MAX_RETRY_WAIT,
        on_retry: OnRetry | None = None,
    ) -> None:
        transport = RetryTransport(max_wait=max_retry_wait, on_retry=on_retry)
        self.client = _generated_client(base_url, api_key, timeout, transport, is_async=False)
        """The generated client, for calling `vigil_client.generated.api` directly."""

    def close(self) -> None:
        """Closes the connections."""
        self.client.get_httpx_client().close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.close()

    def health(self) -> Health:
        """`GET /healthz`."""
        return _result(get_health.sync_detailed(client=self.client))

    def list_scenarios(self) -> ScenarioList:
        """`GET /v1/scenarios`: the built-ins, then the registered ones."""
        return _result(list_scenarios.sync_detailed(client=self.client))

    def get_scenario(self, scenario_id: str) -> ScenarioSummary:
        """`GET /v1/scenarios/{id}`: its spec, lattice, status and summary."""
        return _result(get_scenario.sync_detailed(scenario_id, client=self.client))

    def create_scenario(self, spec: ScenarioSpec | Body) -> ScenarioSummary:
        """`POST /v1/scenarios`: registers a scenario; a large one is precomputed as a job
        (`status` says which), and plans in it wait until it is ready."""
        return _result(create_scenario.sync_detailed(client=self.client, body=_body(spec, ScenarioSpec)))

    def delete_scenario(self, scenario_id: str) -> None:
        """`DELETE /v1/scenarios/{id}`."""
        _result(delete_scenario.sync_detailed(scenario_id, client=self.client))

    def stats(self, scenario_id: str, sensor_type: str | None = None) -> ScenarioStats:
        """`GET /v1/scenarios/{id}/stats`: per-cell statistics, for one sensor type if given."""
        type_ = UNSET if sensor_type is None else sensor_type
        return _result(get_scenario_stats.sync_detailed(scenario_id, client=self.client, type_=type_))

    def plan(self, scenario_id: str, request: PlanRequest | Body) -> PlanResponse:
        """`POST /v1/scenarios/{id}/plan`: every sensor's T-step path."""
        body = _body(request, PlanRequest)
        return _result(plan_scenario.sync_detailed(scenario_id, client=self.client, body=body))

    def plan_inline(self, request: PlanRequestById | PlanRequestWithScenario | Body) -> PlanResponse:
        """`POST /v1/plan`: a plan whose body names (`scenario_id`) or carries (`scenario`) its scenario."""
        body = _body(request, PlanRequestById, PlanRequestWithScenario)
        return _result(plan.sync_detailed(client=self.client, body=body))

    def evaluate(self, scenario_id: str, request: EvaluateBody | Body) -> EvaluateResponse:
        """`POST /v1/scenarios/{id}/evaluate`: scores the given paths."""
        body = _body(request, EvaluateBody)
        return _result(evaluate_scenario.sync_detailed(scenario_id, client=self.client, body=body))

    def fit(self, scenario_id: str, request: FitRequest | Body) -> FitResponse:
        """`POST /v1/scenarios/{id}/fit`: each source's rate fitted to a window of
        observations (with `register`, the fitted scenario registered as well)."""
        body = _body(request, FitRequest)
        return _result(fit_scenario.sync_detailed(scenario_id, client=self.client, body=body))

    def evaluate_inline(
        self, request: EvaluateRequestById | EvaluateRequestWithScenario | Body
    ) -> EvaluateResponse:
        """`POST /v1/evaluate`: `evaluate` with the scenario named or carried in the body."""
        body = _body(request, EvaluateRequestById, EvaluateRequestWithScenario)
        return _result(evaluate.sync_detailed(client=self.client, body=body))

    def session(
        self,
        scenario_id: str | None = None,
        *,
        scenario: ScenarioSpec | Body | None = None,
        **settings: Any,
    ) -> Session:
        """`POST /v1/sessions`: a session in a scenario named or carried (exactly one).

        `settings` are the session's other fields (`horizon`, `coordination`,
        `history_steps`, …). Use the session as a context manager to delete it
        at the end.
        """
        body = _session_body(scenario_id, scenario, settings)
        return Session(self, _result(create_session.sync_detailed(client=self.client, body=body)))


class Session:
    """A session: the server keeps the sensors' history and the tracks between steps.

    Made by `Vigil.session`. As a context manager it deletes the session on exit.
    """

    def __init__(self, vigil: Vigil, info: SessionInfo) -> None:
        self._vigil = vigil
        self.info = info
        """What the server said of the session when it was made or last fetched."""

    @property
    def id(self) -> str:
        """The session's id."""
        return self.info.id

    def step(self, request: StepRequest | Body, *, idempotency_key: str | None = None) -> StepResponse:
        """`POST /v1/sessions/{id}/step`: reports this step and plans from it.

        The step is sent with an `Idempotency-Key` (`idempotency_key`, else a new
        random one), so a resend after a 503, including the client's own waits on
        `Retry-After`, is answered rather than made twice. Pass the key of a step
        whose answer was lost, with the same request, to ask for it again; that
        key with another request is refused (422, `idempotency-key-reused`).
        """
        body = _body(request, StepRequest)
        key = idempotency_key if idempotency_key is not None else uuid.uuid4().hex
        return _result(
            step_session.sync_detailed(self.id, client=self._vigil.client, body=body, idempotency_key=key)
        )

    def refresh(self) -> SessionInfo:
        """`GET /v1/sessions/{id}`: fetches the session's state into `info`."""
        self.info = _result(get_session.sync_detailed(self.id, client=self._vigil.client))
        return self.info

    def delete(self) -> None:
        """`DELETE /v1/sessions/{id}`; a session already gone (expired) is not an error."""
        try:
            _result(delete_session.sync_detailed(self.id, client=self._vigil.client))
        except VigilError as error:
            if error.status != 404:
                raise

    def __enter__(self) -> Self:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.delete()


class AsyncVigil:
    """The asynchronous twin of `Vigil`: the same methods, awaited; `async with` closes it."""

    def __init__(
        self,
        base_url: str = DEFAULT_URL,
        *,
        api_key: str | None = None,
        timeout: float = DEFAULT_TIMEOUT,
        max_retry_wait: float = DEFAULT_MAX_RETRY_WAIT,
        on_retry: OnRetry | None = None,
    ) -> None:
        transport = AsyncRetryTransport(max_wait=max_retry_wait, on_retry=on_retry)
        self.client = _generated_client(base_url, api_key, timeout, transport, is_async=True)
        """The generated client, for calling `vigil_client.generated.api` directly."""

    async def aclose(self) -> None:
        """Closes the connections."""
        await self.client.get_async_httpx_client().aclose()

    async def __aenter__(self) -> Self:
        return self

    async def __aexit__(
        self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.aclose()

    async def health(self) -> Health:
        """`GET /healthz`."""
        return _result(await get_health.asyncio_detailed(client=self.client))

    async def list_scenarios(self) -> ScenarioList:
        """`GET /v1/scenarios`."""
        return _result(await list_scenarios.asyncio_detailed(client=self.client))

    async def get_scenario(self, scenario_id: str) -> ScenarioSummary:
        """`GET /v1/scenarios/{id}`."""
        return _result(await get_scenario.asyncio_detailed(scenario_id, client=self.client))

    async def create_scenario(self, spec: ScenarioSpec | Body) -> ScenarioSummary:
        """`POST /v1/scenarios`."""
        body = _body(spec, ScenarioSpec)
        return _result(await create_scenario.asyncio_detailed(client=self.client, body=body))

    async def delete_scenario(self, scenario_id: str) -> None:
        """`DELETE /v1/scenarios/{id}`."""
        _result(await delete_scenario.asyncio_detailed(scenario_id, client=self.client))

    async def stats(self, scenario_id: str, sensor_type: str | None = None) -> ScenarioStats:
        """`GET /v1/scenarios/{id}/stats`."""
        type_ = UNSET if sensor_type is None else sensor_type
        return _result(await get_scenario_stats.asyncio_detailed(scenario_id, client=self.client, type_=type_))

    async def plan(self, scenario_id: str, request: PlanRequest | Body) -> PlanResponse:
        """`POST /v1/scenarios/{id}/plan`."""
        body = _body(request, PlanRequest)
        return _result(await plan_scenario.asyncio_detailed(scenario_id, client=self.client, body=body))

    async def plan_inline(self, request: PlanRequestById | PlanRequestWithScenario | Body) -> PlanResponse:
        """`POST /v1/plan`."""
        body = _body(request, PlanRequestById, PlanRequestWithScenario)
        return _result(await plan.asyncio_detailed(client=self.client, body=body))

    async def evaluate(self, scenario_id: str, request: EvaluateBody | Body) -> EvaluateResponse:
        """`POST /v1/scenarios/{id}/evaluate`."""
        body = _body(request, EvaluateBody)
        return _result(await evaluate_scenario.asyncio_detailed(scenario_id, client=self.client, body=body))

    async def fit(self, scenario_id: str, request: FitRequest | Body) -> FitResponse:
        """`POST /v1/scenarios/{id}/fit`."""
        body = _body(request, FitRequest)
        return _result(await fit_scenario.asyncio_detailed(scenario_id, client=self.client, body=body))

    async def evaluate_inline(
        self, request: EvaluateRequestById | EvaluateRequestWithScenario | Body
    ) -> EvaluateResponse:
        """`POST /v1/evaluate`."""
        body = _body(request, EvaluateRequestById, EvaluateRequestWithScenario)
        return _result(await evaluate.asyncio_detailed(client=self.client, body=body))

    async def session(
        self,
        scenario_id: str | None = None,
        *,
        scenario: ScenarioSpec | Body | None = None,
        **settings: Any,
    ) -> AsyncSession:
        """`POST /v1/sessions`; `async with` the result deletes it at the end."""
        body = _session_body(scenario_id, scenario, settings)
        return AsyncSession(self, _result(await create_session.asyncio_detailed(client=self.client, body=body)))


class AsyncSession:
    """The asynchronous twin of `Session`."""

    def __init__(self, vigil: AsyncVigil, info: SessionInfo) -> None:
        self._vigil = vigil
        self.info = info
        """What the server said of the session when it was made or last fetched."""

    @property
    def id(self) -> str:
        """The session's id."""
        return self.info.id

    async def step(self, request: StepRequest | Body, *, idempotency_key: str | None = None) -> StepResponse:
        """`POST /v1/sessions/{id}/step`, with an `Idempotency-Key` as in `Session.step`."""
        body = _body(request, StepRequest)
        key = idempotency_key if idempotency_key is not None else uuid.uuid4().hex
        return _result(
            await step_session.asyncio_detailed(self.id, client=self._vigil.client, body=body, idempotency_key=key)
        )

    async def refresh(self) -> SessionInfo:
        """`GET /v1/sessions/{id}`."""
        self.info = _result(await get_session.asyncio_detailed(self.id, client=self._vigil.client))
        return self.info

    async def delete(self) -> None:
        """`DELETE /v1/sessions/{id}`; a session already gone is not an error."""
        try:
            _result(await delete_session.asyncio_detailed(self.id, client=self._vigil.client))
        except VigilError as error:
            if error.status != 404:
                raise

    async def __aenter__(self) -> Self:
        return self

    async def __aexit__(
        self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.delete()
