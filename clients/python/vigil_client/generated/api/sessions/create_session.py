from http import HTTPStatus
from typing import Any

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response
from ... import errors

from ...models.problem import Problem
from ...models.session_info import SessionInfo
from ...models.session_request_by_id import SessionRequestById
from ...models.session_request_with_scenario import SessionRequestWithScenario


def _get_kwargs(
    *,
    body: SessionRequestById | SessionRequestWithScenario,
) -> dict[str, Any]:
    headers: dict[str, Any] = {}

    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/sessions",
    }

    if isinstance(body, SessionRequestById):
        _kwargs["json"] = body.to_dict()
    else:
        _kwargs["json"] = body.to_dict()

    headers["Content-Type"] = "application/json"

    _kwargs["headers"] = headers
    return _kwargs


def _parse_response(
    *, client: AuthenticatedClient | Client, response: httpx.Response
) -> Problem | SessionInfo | None:
    if response.status_code == 201:
        response_201 = SessionInfo.from_dict(response.json())

        return response_201

    if response.status_code == 400:
        response_400 = Problem.from_dict(response.json())

        return response_400

    if response.status_code == 401:
        response_401 = Problem.from_dict(response.json())

        return response_401

    if response.status_code == 404:
        response_404 = Problem.from_dict(response.json())

        return response_404

    if response.status_code == 413:
        response_413 = Problem.from_dict(response.json())

        return response_413

    if response.status_code == 422:
        response_422 = Problem.from_dict(response.json())

        return response_422

    if response.status_code == 503:
        response_503 = Problem.from_dict(response.json())

        return response_503

    if response.status_code == 504:
        response_504 = Problem.from_dict(response.json())

        return response_504

    if client.raise_on_unexpected_status:
        raise errors.UnexpectedStatus(response.status_code, response.content)
    else:
        return None


def _build_response(
    *, client: AuthenticatedClient | Client, response: httpx.Response
) -> Response[Problem | SessionInfo]:
    return Response(
        status_code=HTTPStatus(response.status_code),
        content=response.content,
        headers=response.headers,
        parsed=_parse_response(client=client, response=response),
    )


def sync_detailed(
    *,
    client: AuthenticatedClient,
    body: SessionRequestById | SessionRequestWithScenario,
) -> Response[Problem | SessionInfo]:
    """Open a session

     Opens a session for a client that plans every step: the server keeps the sensors' past positions and
    the targets' tracks, so each step sends only the sensors now and the targets detected now. The body
    names the scenario (`scenario_id`, or an inline `scenario` as in `POST /v1/plan`) and the defaults
    of its steps; `history_steps` (0..=128, 16 by default) is how many steps of history it keeps.
    Without a database a session lives in the memory of the replica that created it: route its requests
    there. With `--database-url` it is kept in the database, and every replica on it serves it. A
    session idle for `--session-ttl-s` (600 s), or the least recently used past `--max-sessions` (10
    000), is dropped. With `learn_rates: true` the session learns the sources' rates from its detections
    (each needs an `id`), plans with them and reports them as `rates` at every step (see
    `docs/learning.md`); only a scenario precomputed within `--sync-precompute-ms` may learn.

    Args:
        body (SessionRequestById | SessionRequestWithScenario): Body of `POST /v1/sessions`:
            exactly one of `scenario_id` and
            `scenario`, and the defaults of the session's steps.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[Problem | SessionInfo]
    """

    kwargs = _get_kwargs(
        body=body,
    )

    response = client.get_httpx_client().request(
        **kwargs,
    )

    return _build_response(client=client, response=response)


def sync(
    *,
    client: AuthenticatedClient,
    body: SessionRequestById | SessionRequestWithScenario,
) -> Problem | SessionInfo | None:
    """Open a session

     Opens a session for a client that plans every step: the server keeps the sensors' past positions and
    the targets' tracks, so each step sends only the sensors now and the targets detected now. The body
    names the scenario (`scenario_id`, or an inline `scenario` as in `POST /v1/plan`) and the defaults
    of its steps; `history_steps` (0..=128, 16 by default) is how many steps of history it keeps.
    Without a database a session lives in the memory of the replica that created it: route its requests
    there. With `--database-url` it is kept in the database, and every replica on it serves it. A
    session idle for `--session-ttl-s` (600 s), or the least recently used past `--max-sessions` (10
    000), is dropped. With `learn_rates: true` the session learns the sources' rates from its detections
    (each needs an `id`), plans with them and reports them as `rates` at every step (see
    `docs/learning.md`); only a scenario precomputed within `--sync-precompute-ms` may learn.

    Args:
        body (SessionRequestById | SessionRequestWithScenario): Body of `POST /v1/sessions`:
            exactly one of `scenario_id` and
            `scenario`, and the defaults of the session's steps.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Problem | SessionInfo
    """

    return sync_detailed(
        client=client,
        body=body,
    ).parsed


async def asyncio_detailed(
    *,
    client: AuthenticatedClient,
    body: SessionRequestById | SessionRequestWithScenario,
) -> Response[Problem | SessionInfo]:
    """Open a session

     Opens a session for a client that plans every step: the server keeps the sensors' past positions and
    the targets' tracks, so each step sends only the sensors now and the targets detected now. The body
    names the scenario (`scenario_id`, or an inline `scenario` as in `POST /v1/plan`) and the defaults
    of its steps; `history_steps` (0..=128, 16 by default) is how many steps of history it keeps.
    Without a database a session lives in the memory of the replica that created it: route its requests
    there. With `--database-url` it is kept in the database, and every replica on it serves it. A
    session idle for `--session-ttl-s` (600 s), or the least recently used past `--max-sessions` (10
    000), is dropped. With `learn_rates: true` the session learns the sources' rates from its detections
    (each needs an `id`), plans with them and reports them as `rates` at every step (see
    `docs/learning.md`); only a scenario precomputed within `--sync-precompute-ms` may learn.

    Args:
        body (SessionRequestById | SessionRequestWithScenario): Body of `POST /v1/sessions`:
            exactly one of `scenario_id` and
            `scenario`, and the defaults of the session's steps.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[Problem | SessionInfo]
    """

    kwargs = _get_kwargs(
        body=body,
    )

    response = await client.get_async_httpx_client().request(**kwargs)

    return _build_response(client=client, response=response)


async def asyncio(
    *,
    client: AuthenticatedClient,
    body: SessionRequestById | SessionRequestWithScenario,
) -> Problem | SessionInfo | None:
    """Open a session

     Opens a session for a client that plans every step: the server keeps the sensors' past positions and
    the targets' tracks, so each step sends only the sensors now and the targets detected now. The body
    names the scenario (`scenario_id`, or an inline `scenario` as in `POST /v1/plan`) and the defaults
    of its steps; `history_steps` (0..=128, 16 by default) is how many steps of history it keeps.
    Without a database a session lives in the memory of the replica that created it: route its requests
    there. With `--database-url` it is kept in the database, and every replica on it serves it. A
    session idle for `--session-ttl-s` (600 s), or the least recently used past `--max-sessions` (10
    000), is dropped. With `learn_rates: true` the session learns the sources' rates from its detections
    (each needs an `id`), plans with them and reports them as `rates` at every step (see
    `docs/learning.md`); only a scenario precomputed within `--sync-precompute-ms` may learn.

    Args:
        body (SessionRequestById | SessionRequestWithScenario): Body of `POST /v1/sessions`:
            exactly one of `scenario_id` and
            `scenario`, and the defaults of the session's steps.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Problem | SessionInfo
    """

    return (
        await asyncio_detailed(
            client=client,
            body=body,
        )
    ).parsed
