from http import HTTPStatus
from typing import Any

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response
from ... import errors

from ...models.problem import Problem
from ...models.scenario_spec import ScenarioSpec
from ...models.scenario_summary import ScenarioSummary


def _get_kwargs(
    *,
    body: ScenarioSpec,
) -> dict[str, Any]:
    headers: dict[str, Any] = {}

    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/scenarios",
    }

    _kwargs["json"] = body.to_dict()

    headers["Content-Type"] = "application/json"

    _kwargs["headers"] = headers
    return _kwargs


def _parse_response(
    *, client: AuthenticatedClient | Client, response: httpx.Response
) -> Problem | ScenarioSummary | None:
    if response.status_code == 200:
        response_200 = ScenarioSummary.from_dict(response.json())

        return response_200

    if response.status_code == 201:
        response_201 = ScenarioSummary.from_dict(response.json())

        return response_201

    if response.status_code == 202:
        response_202 = ScenarioSummary.from_dict(response.json())

        return response_202

    if response.status_code == 400:
        response_400 = Problem.from_dict(response.json())

        return response_400

    if response.status_code == 401:
        response_401 = Problem.from_dict(response.json())

        return response_401

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
) -> Response[Problem | ScenarioSummary]:
    return Response(
        status_code=HTTPStatus(response.status_code),
        content=response.content,
        headers=response.headers,
        parsed=_parse_response(client=client, response=response),
    )


def sync_detailed(
    *,
    client: AuthenticatedClient,
    body: ScenarioSpec,
) -> Response[Problem | ScenarioSummary]:
    """Register a scenario

     Validates the spec, precomputes its per-cell statistics and registers it under an id derived from
    the canonical spec (`s-` and 16 hex digits), so posting the same spec again is idempotent: 201 the
    first time, 200 with the registered scenario after.

    A scenario whose precomputation is predicted to take longer than the server's synchronous budget
    (`--sync-precompute-ms`, 1 s by default; the prediction is the summary's `predicted_precompute_ms`)
    is precomputed as a background job instead: the answer is 202 at once with its `Location`, the spec
    is stored durably (a restart resumes the job), and `GET` on that location shows `status` `queued`
    (with its `queue_position`), then `precomputing` (with `progress` rising to 1 and `eta_s`), then
    `ready`. Meanwhile plans and statistics on it answer 503 with `Retry-After`, and `DELETE` cancels
    the job. Jobs run one at a time by default (`--precompute-jobs`); past `--precompute-queue` waiting
    jobs a registration gets 503. Rules no schema can state (each a 422 whose `detail` names the field):
    the zone's width and height are whole multiples of `cell_size`, and the lattice has at most
    4,000,000 cells; every source lies strictly outside the zone, its coordinates within ±1e12; a source
    without `direction` is beside exactly one edge of the zone or gives a `heading` whose half-plane
    holds the zone; some direction of each source's cone enters the zone; `target_speed` is required
    when some source gives no `speeds`; a source's weights sum to a finite number; Σ rate·diagonal/speed
    over the speed classes is at most 1e9 (the statistics stay finite); each obstacle's polygon is
    convex, with no repeated vertex and no three consecutive ones collinear, and not wholly outside the
    zone; no source lies inside a building, and some direction of each source's cone enters the zone
    before any building.

    Args:
        body (ScenarioSpec): A scenario as clients send it.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[Problem | ScenarioSummary]
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
    body: ScenarioSpec,
) -> Problem | ScenarioSummary | None:
    """Register a scenario

     Validates the spec, precomputes its per-cell statistics and registers it under an id derived from
    the canonical spec (`s-` and 16 hex digits), so posting the same spec again is idempotent: 201 the
    first time, 200 with the registered scenario after.

    A scenario whose precomputation is predicted to take longer than the server's synchronous budget
    (`--sync-precompute-ms`, 1 s by default; the prediction is the summary's `predicted_precompute_ms`)
    is precomputed as a background job instead: the answer is 202 at once with its `Location`, the spec
    is stored durably (a restart resumes the job), and `GET` on that location shows `status` `queued`
    (with its `queue_position`), then `precomputing` (with `progress` rising to 1 and `eta_s`), then
    `ready`. Meanwhile plans and statistics on it answer 503 with `Retry-After`, and `DELETE` cancels
    the job. Jobs run one at a time by default (`--precompute-jobs`); past `--precompute-queue` waiting
    jobs a registration gets 503. Rules no schema can state (each a 422 whose `detail` names the field):
    the zone's width and height are whole multiples of `cell_size`, and the lattice has at most
    4,000,000 cells; every source lies strictly outside the zone, its coordinates within ±1e12; a source
    without `direction` is beside exactly one edge of the zone or gives a `heading` whose half-plane
    holds the zone; some direction of each source's cone enters the zone; `target_speed` is required
    when some source gives no `speeds`; a source's weights sum to a finite number; Σ rate·diagonal/speed
    over the speed classes is at most 1e9 (the statistics stay finite); each obstacle's polygon is
    convex, with no repeated vertex and no three consecutive ones collinear, and not wholly outside the
    zone; no source lies inside a building, and some direction of each source's cone enters the zone
    before any building.

    Args:
        body (ScenarioSpec): A scenario as clients send it.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Problem | ScenarioSummary
    """

    return sync_detailed(
        client=client,
        body=body,
    ).parsed


async def asyncio_detailed(
    *,
    client: AuthenticatedClient,
    body: ScenarioSpec,
) -> Response[Problem | ScenarioSummary]:
    """Register a scenario

     Validates the spec, precomputes its per-cell statistics and registers it under an id derived from
    the canonical spec (`s-` and 16 hex digits), so posting the same spec again is idempotent: 201 the
    first time, 200 with the registered scenario after.

    A scenario whose precomputation is predicted to take longer than the server's synchronous budget
    (`--sync-precompute-ms`, 1 s by default; the prediction is the summary's `predicted_precompute_ms`)
    is precomputed as a background job instead: the answer is 202 at once with its `Location`, the spec
    is stored durably (a restart resumes the job), and `GET` on that location shows `status` `queued`
    (with its `queue_position`), then `precomputing` (with `progress` rising to 1 and `eta_s`), then
    `ready`. Meanwhile plans and statistics on it answer 503 with `Retry-After`, and `DELETE` cancels
    the job. Jobs run one at a time by default (`--precompute-jobs`); past `--precompute-queue` waiting
    jobs a registration gets 503. Rules no schema can state (each a 422 whose `detail` names the field):
    the zone's width and height are whole multiples of `cell_size`, and the lattice has at most
    4,000,000 cells; every source lies strictly outside the zone, its coordinates within ±1e12; a source
    without `direction` is beside exactly one edge of the zone or gives a `heading` whose half-plane
    holds the zone; some direction of each source's cone enters the zone; `target_speed` is required
    when some source gives no `speeds`; a source's weights sum to a finite number; Σ rate·diagonal/speed
    over the speed classes is at most 1e9 (the statistics stay finite); each obstacle's polygon is
    convex, with no repeated vertex and no three consecutive ones collinear, and not wholly outside the
    zone; no source lies inside a building, and some direction of each source's cone enters the zone
    before any building.

    Args:
        body (ScenarioSpec): A scenario as clients send it.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[Problem | ScenarioSummary]
    """

    kwargs = _get_kwargs(
        body=body,
    )

    response = await client.get_async_httpx_client().request(**kwargs)

    return _build_response(client=client, response=response)


async def asyncio(
    *,
    client: AuthenticatedClient,
    body: ScenarioSpec,
) -> Problem | ScenarioSummary | None:
    """Register a scenario

     Validates the spec, precomputes its per-cell statistics and registers it under an id derived from
    the canonical spec (`s-` and 16 hex digits), so posting the same spec again is idempotent: 201 the
    first time, 200 with the registered scenario after.

    A scenario whose precomputation is predicted to take longer than the server's synchronous budget
    (`--sync-precompute-ms`, 1 s by default; the prediction is the summary's `predicted_precompute_ms`)
    is precomputed as a background job instead: the answer is 202 at once with its `Location`, the spec
    is stored durably (a restart resumes the job), and `GET` on that location shows `status` `queued`
    (with its `queue_position`), then `precomputing` (with `progress` rising to 1 and `eta_s`), then
    `ready`. Meanwhile plans and statistics on it answer 503 with `Retry-After`, and `DELETE` cancels
    the job. Jobs run one at a time by default (`--precompute-jobs`); past `--precompute-queue` waiting
    jobs a registration gets 503. Rules no schema can state (each a 422 whose `detail` names the field):
    the zone's width and height are whole multiples of `cell_size`, and the lattice has at most
    4,000,000 cells; every source lies strictly outside the zone, its coordinates within ±1e12; a source
    without `direction` is beside exactly one edge of the zone or gives a `heading` whose half-plane
    holds the zone; some direction of each source's cone enters the zone; `target_speed` is required
    when some source gives no `speeds`; a source's weights sum to a finite number; Σ rate·diagonal/speed
    over the speed classes is at most 1e9 (the statistics stay finite); each obstacle's polygon is
    convex, with no repeated vertex and no three consecutive ones collinear, and not wholly outside the
    zone; no source lies inside a building, and some direction of each source's cone enters the zone
    before any building.

    Args:
        body (ScenarioSpec): A scenario as clients send it.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Problem | ScenarioSummary
    """

    return (
        await asyncio_detailed(
            client=client,
            body=body,
        )
    ).parsed
