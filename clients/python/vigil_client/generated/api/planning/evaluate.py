from http import HTTPStatus
from typing import Any

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response
from ... import errors

from ...models.evaluate_request_by_id import EvaluateRequestById
from ...models.evaluate_request_with_scenario import EvaluateRequestWithScenario
from ...models.evaluate_response import EvaluateResponse
from ...models.problem import Problem


def _get_kwargs(
    *,
    body: EvaluateRequestById | EvaluateRequestWithScenario,
) -> dict[str, Any]:
    headers: dict[str, Any] = {}

    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/evaluate",
    }

    if isinstance(body, EvaluateRequestById):
        _kwargs["json"] = body.to_dict()
    else:
        _kwargs["json"] = body.to_dict()

    headers["Content-Type"] = "application/json"

    _kwargs["headers"] = headers
    return _kwargs


def _parse_response(
    *, client: AuthenticatedClient | Client, response: httpx.Response
) -> EvaluateResponse | Problem | None:
    if response.status_code == 200:
        response_200 = EvaluateResponse.from_dict(response.json())

        return response_200

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
) -> Response[EvaluateResponse | Problem]:
    return Response(
        status_code=HTTPStatus(response.status_code),
        content=response.content,
        headers=response.headers,
        parsed=_parse_response(client=client, response=response),
    )


def sync_detailed(
    *,
    client: AuthenticatedClient,
    body: EvaluateRequestById | EvaluateRequestWithScenario,
) -> Response[EvaluateResponse | Problem]:
    """Score given paths in a scenario named or sent inline

     The same scoring as `POST /v1/scenarios/{id}/evaluate`, with the scenario in the body as in `POST
    /v1/plan`: exactly one of `scenario_id` and `scenario`. Rules no schema can state (each a 422 whose
    `detail` names the field): every sensor and history position lies in the scenario's zone, and sensor
    ids are unique; no ground sensor (a type not `elevated`), now or in the history, stands on a cell
    whose centre lies in a building; and with obstacles the estimator is `exact`. The paths' rules (each
    a 422 whose `detail` names the field): one path per sensor, each naming a sensor of `sensors` once,
    of exactly T cells (the horizon's steps 1..T), every cell on the lattice and outside the no-go zones
    (and, for a ground sensor, outside the buildings), each step a move of at most the sensor type's
    speed (king moves) that free cells allow, from the sensor's own cell. Rules no schema can state
    (each a 422 whose `detail` names the field): the zone's width and height are whole multiples of
    `cell_size`, and the lattice has at most 4,000,000 cells; every source lies strictly outside the
    zone, its coordinates within ±1e12; a source without `direction` is beside exactly one edge of the
    zone or gives a `heading` whose half-plane holds the zone; some direction of each source's cone
    enters the zone; `target_speed` is required when some source gives no `speeds`; a source's weights
    sum to a finite number; Σ rate·diagonal/speed over the speed classes is at most 1e9 (the statistics
    stay finite); each obstacle's polygon is convex, with no repeated vertex and no three consecutive
    ones collinear, and not wholly outside the zone; no source lies inside a building, and some
    direction of each source's cone enters the zone before any building.

    Args:
        body (EvaluateRequestById | EvaluateRequestWithScenario): Body of `POST /v1/evaluate`: the
            body of `POST
            /v1/scenarios/{id}/evaluate` plus exactly one of `scenario_id` and
            `scenario`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[EvaluateResponse | Problem]
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
    body: EvaluateRequestById | EvaluateRequestWithScenario,
) -> EvaluateResponse | Problem | None:
    """Score given paths in a scenario named or sent inline

     The same scoring as `POST /v1/scenarios/{id}/evaluate`, with the scenario in the body as in `POST
    /v1/plan`: exactly one of `scenario_id` and `scenario`. Rules no schema can state (each a 422 whose
    `detail` names the field): every sensor and history position lies in the scenario's zone, and sensor
    ids are unique; no ground sensor (a type not `elevated`), now or in the history, stands on a cell
    whose centre lies in a building; and with obstacles the estimator is `exact`. The paths' rules (each
    a 422 whose `detail` names the field): one path per sensor, each naming a sensor of `sensors` once,
    of exactly T cells (the horizon's steps 1..T), every cell on the lattice and outside the no-go zones
    (and, for a ground sensor, outside the buildings), each step a move of at most the sensor type's
    speed (king moves) that free cells allow, from the sensor's own cell. Rules no schema can state
    (each a 422 whose `detail` names the field): the zone's width and height are whole multiples of
    `cell_size`, and the lattice has at most 4,000,000 cells; every source lies strictly outside the
    zone, its coordinates within ±1e12; a source without `direction` is beside exactly one edge of the
    zone or gives a `heading` whose half-plane holds the zone; some direction of each source's cone
    enters the zone; `target_speed` is required when some source gives no `speeds`; a source's weights
    sum to a finite number; Σ rate·diagonal/speed over the speed classes is at most 1e9 (the statistics
    stay finite); each obstacle's polygon is convex, with no repeated vertex and no three consecutive
    ones collinear, and not wholly outside the zone; no source lies inside a building, and some
    direction of each source's cone enters the zone before any building.

    Args:
        body (EvaluateRequestById | EvaluateRequestWithScenario): Body of `POST /v1/evaluate`: the
            body of `POST
            /v1/scenarios/{id}/evaluate` plus exactly one of `scenario_id` and
            `scenario`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        EvaluateResponse | Problem
    """

    return sync_detailed(
        client=client,
        body=body,
    ).parsed


async def asyncio_detailed(
    *,
    client: AuthenticatedClient,
    body: EvaluateRequestById | EvaluateRequestWithScenario,
) -> Response[EvaluateResponse | Problem]:
    """Score given paths in a scenario named or sent inline

     The same scoring as `POST /v1/scenarios/{id}/evaluate`, with the scenario in the body as in `POST
    /v1/plan`: exactly one of `scenario_id` and `scenario`. Rules no schema can state (each a 422 whose
    `detail` names the field): every sensor and history position lies in the scenario's zone, and sensor
    ids are unique; no ground sensor (a type not `elevated`), now or in the history, stands on a cell
    whose centre lies in a building; and with obstacles the estimator is `exact`. The paths' rules (each
    a 422 whose `detail` names the field): one path per sensor, each naming a sensor of `sensors` once,
    of exactly T cells (the horizon's steps 1..T), every cell on the lattice and outside the no-go zones
    (and, for a ground sensor, outside the buildings), each step a move of at most the sensor type's
    speed (king moves) that free cells allow, from the sensor's own cell. Rules no schema can state
    (each a 422 whose `detail` names the field): the zone's width and height are whole multiples of
    `cell_size`, and the lattice has at most 4,000,000 cells; every source lies strictly outside the
    zone, its coordinates within ±1e12; a source without `direction` is beside exactly one edge of the
    zone or gives a `heading` whose half-plane holds the zone; some direction of each source's cone
    enters the zone; `target_speed` is required when some source gives no `speeds`; a source's weights
    sum to a finite number; Σ rate·diagonal/speed over the speed classes is at most 1e9 (the statistics
    stay finite); each obstacle's polygon is convex, with no repeated vertex and no three consecutive
    ones collinear, and not wholly outside the zone; no source lies inside a building, and some
    direction of each source's cone enters the zone before any building.

    Args:
        body (EvaluateRequestById | EvaluateRequestWithScenario): Body of `POST /v1/evaluate`: the
            body of `POST
            /v1/scenarios/{id}/evaluate` plus exactly one of `scenario_id` and
            `scenario`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[EvaluateResponse | Problem]
    """

    kwargs = _get_kwargs(
        body=body,
    )

    response = await client.get_async_httpx_client().request(**kwargs)

    return _build_response(client=client, response=response)


async def asyncio(
    *,
    client: AuthenticatedClient,
    body: EvaluateRequestById | EvaluateRequestWithScenario,
) -> EvaluateResponse | Problem | None:
    """Score given paths in a scenario named or sent inline

     The same scoring as `POST /v1/scenarios/{id}/evaluate`, with the scenario in the body as in `POST
    /v1/plan`: exactly one of `scenario_id` and `scenario`. Rules no schema can state (each a 422 whose
    `detail` names the field): every sensor and history position lies in the scenario's zone, and sensor
    ids are unique; no ground sensor (a type not `elevated`), now or in the history, stands on a cell
    whose centre lies in a building; and with obstacles the estimator is `exact`. The paths' rules (each
    a 422 whose `detail` names the field): one path per sensor, each naming a sensor of `sensors` once,
    of exactly T cells (the horizon's steps 1..T), every cell on the lattice and outside the no-go zones
    (and, for a ground sensor, outside the buildings), each step a move of at most the sensor type's
    speed (king moves) that free cells allow, from the sensor's own cell. Rules no schema can state
    (each a 422 whose `detail` names the field): the zone's width and height are whole multiples of
    `cell_size`, and the lattice has at most 4,000,000 cells; every source lies strictly outside the
    zone, its coordinates within ±1e12; a source without `direction` is beside exactly one edge of the
    zone or gives a `heading` whose half-plane holds the zone; some direction of each source's cone
    enters the zone; `target_speed` is required when some source gives no `speeds`; a source's weights
    sum to a finite number; Σ rate·diagonal/speed over the speed classes is at most 1e9 (the statistics
    stay finite); each obstacle's polygon is convex, with no repeated vertex and no three consecutive
    ones collinear, and not wholly outside the zone; no source lies inside a building, and some
    direction of each source's cone enters the zone before any building.

    Args:
        body (EvaluateRequestById | EvaluateRequestWithScenario): Body of `POST /v1/evaluate`: the
            body of `POST
            /v1/scenarios/{id}/evaluate` plus exactly one of `scenario_id` and
            `scenario`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        EvaluateResponse | Problem
    """

    return (
        await asyncio_detailed(
            client=client,
            body=body,
        )
    ).parsed
