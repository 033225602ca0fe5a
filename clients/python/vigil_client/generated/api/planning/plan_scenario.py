from http import HTTPStatus
from typing import Any
from urllib.parse import quote

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response
from ... import errors

from ...models.plan_request import PlanRequest
from ...models.plan_response import PlanResponse
from ...models.problem import Problem


def _get_kwargs(
    id: str,
    *,
    body: PlanRequest,
) -> dict[str, Any]:
    headers: dict[str, Any] = {}

    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/scenarios/{id}/plan".format(
            id=quote(str(id), safe=""),
        ),
    }

    _kwargs["json"] = body.to_dict()

    headers["Content-Type"] = "application/json"

    _kwargs["headers"] = headers
    return _kwargs


def _parse_response(
    *, client: AuthenticatedClient | Client, response: httpx.Response
) -> PlanResponse | Problem | None:
    if response.status_code == 200:
        response_200 = PlanResponse.from_dict(response.json())

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
) -> Response[PlanResponse | Problem]:
    return Response(
        status_code=HTTPStatus(response.status_code),
        content=response.content,
        headers=response.headers,
        parsed=_parse_response(client=client, response=response),
    )


def sync_detailed(
    id: str,
    *,
    client: AuthenticatedClient,
    body: PlanRequest,
) -> Response[PlanResponse | Problem]:
    """Plan the sensors' next T steps

     Plans coordinated T-step paths for the sensors that maximise the expected number of distinct targets
    detected, given the targets reported now (and optionally the sensors' past positions). Positions are
    snapped to the scenario's lattice. The scenario is looked up before the body is read, so an unknown
    id is 404 whatever the body (and one still being precomputed 503). A plan whose cost the server
    predicts above its limit (`--max-plan-ms`, 2 s of CPU by default) is refused with 422 before any
    work starts. Rules no schema can state (each a 422 whose `detail` names the field): every sensor and
    history position lies in the scenario's zone, and sensor ids are unique; no ground sensor (a type
    not `elevated`), now or in the history, stands on a cell whose centre lies in a building; and with
    obstacles the estimator is `exact`.

    Args:
        id (str):
        body (PlanRequest): Body of `POST /v1/scenarios/{id}/plan`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[PlanResponse | Problem]
    """

    kwargs = _get_kwargs(
        id=id,
        body=body,
    )

    response = client.get_httpx_client().request(
        **kwargs,
    )

    return _build_response(client=client, response=response)


def sync(
    id: str,
    *,
    client: AuthenticatedClient,
    body: PlanRequest,
) -> PlanResponse | Problem | None:
    """Plan the sensors' next T steps

     Plans coordinated T-step paths for the sensors that maximise the expected number of distinct targets
    detected, given the targets reported now (and optionally the sensors' past positions). Positions are
    snapped to the scenario's lattice. The scenario is looked up before the body is read, so an unknown
    id is 404 whatever the body (and one still being precomputed 503). A plan whose cost the server
    predicts above its limit (`--max-plan-ms`, 2 s of CPU by default) is refused with 422 before any
    work starts. Rules no schema can state (each a 422 whose `detail` names the field): every sensor and
    history position lies in the scenario's zone, and sensor ids are unique; no ground sensor (a type
    not `elevated`), now or in the history, stands on a cell whose centre lies in a building; and with
    obstacles the estimator is `exact`.

    Args:
        id (str):
        body (PlanRequest): Body of `POST /v1/scenarios/{id}/plan`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        PlanResponse | Problem
    """

    return sync_detailed(
        id=id,
        client=client,
        body=body,
    ).parsed


async def asyncio_detailed(
    id: str,
    *,
    client: AuthenticatedClient,
    body: PlanRequest,
) -> Response[PlanResponse | Problem]:
    """Plan the sensors' next T steps

     Plans coordinated T-step paths for the sensors that maximise the expected number of distinct targets
    detected, given the targets reported now (and optionally the sensors' past positions). Positions are
    snapped to the scenario's lattice. The scenario is looked up before the body is read, so an unknown
    id is 404 whatever the body (and one still being precomputed 503). A plan whose cost the server
    predicts above its limit (`--max-plan-ms`, 2 s of CPU by default) is refused with 422 before any
    work starts. Rules no schema can state (each a 422 whose `detail` names the field): every sensor and
    history position lies in the scenario's zone, and sensor ids are unique; no ground sensor (a type
    not `elevated`), now or in the history, stands on a cell whose centre lies in a building; and with
    obstacles the estimator is `exact`.

    Args:
        id (str):
        body (PlanRequest): Body of `POST /v1/scenarios/{id}/plan`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[PlanResponse | Problem]
    """

    kwargs = _get_kwargs(
        id=id,
        body=body,
    )

    response = await client.get_async_httpx_client().request(**kwargs)

    return _build_response(client=client, response=response)


async def asyncio(
    id: str,
    *,
    client: AuthenticatedClient,
    body: PlanRequest,
) -> PlanResponse | Problem | None:
    """Plan the sensors' next T steps

     Plans coordinated T-step paths for the sensors that maximise the expected number of distinct targets
    detected, given the targets reported now (and optionally the sensors' past positions). Positions are
    snapped to the scenario's lattice. The scenario is looked up before the body is read, so an unknown
    id is 404 whatever the body (and one still being precomputed 503). A plan whose cost the server
    predicts above its limit (`--max-plan-ms`, 2 s of CPU by default) is refused with 422 before any
    work starts. Rules no schema can state (each a 422 whose `detail` names the field): every sensor and
    history position lies in the scenario's zone, and sensor ids are unique; no ground sensor (a type
    not `elevated`), now or in the history, stands on a cell whose centre lies in a building; and with
    obstacles the estimator is `exact`.

    Args:
        id (str):
        body (PlanRequest): Body of `POST /v1/scenarios/{id}/plan`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        PlanResponse | Problem
    """

    return (
        await asyncio_detailed(
            id=id,
            client=client,
            body=body,
        )
    ).parsed
