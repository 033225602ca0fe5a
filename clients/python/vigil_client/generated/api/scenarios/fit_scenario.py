from http import HTTPStatus
from typing import Any
from urllib.parse import quote

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response
from ... import errors

from ...models.fit_request import FitRequest
from ...models.fit_response import FitResponse
from ...models.problem import Problem


def _get_kwargs(
    id: str,
    *,
    body: FitRequest,
) -> dict[str, Any]:
    headers: dict[str, Any] = {}

    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/scenarios/{id}/fit".format(
            id=quote(str(id), safe=""),
        ),
    }

    _kwargs["json"] = body.to_dict()

    headers["Content-Type"] = "application/json"

    _kwargs["headers"] = headers
    return _kwargs


def _parse_response(
    *, client: AuthenticatedClient | Client, response: httpx.Response
) -> FitResponse | Problem | None:
    if response.status_code == 200:
        response_200 = FitResponse.from_dict(response.json())

        return response_200

    if response.status_code == 201:
        response_201 = FitResponse.from_dict(response.json())

        return response_201

    if response.status_code == 202:
        response_202 = FitResponse.from_dict(response.json())

        return response_202

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
) -> Response[FitResponse | Problem]:
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
    body: FitRequest,
) -> Response[FitResponse | Problem]:
    """Fit the sources' rates to what the sensors saw

     Estimates each source's Poisson rate from a window of consecutive steps (oldest first, 1 to 500):
    each step's sensors (their looks, at cell centres, as in a plan) and the targets they detected, each
    with a track id that follows it across steps (each target counts once). A source's distinct detected
    targets are Poisson with mean `rate × exposure`, where `exposure` (steps) counts every target in the
    zone during the window that the looks could have detected, those inside at its first step included;
    each detected target is traced back along its velocity to the sources whose position, takeoff cone
    and speeds explain it (shared in proportion to their rates and densities when several do), within
    `tolerance`. The answer is each source's posterior mean `rate` and 95% credible `interval` under a
    Gamma prior (`scenario`: shape 1, mean the spec's rate; `flat`: uniform, Gamma(N + 1, E)); the
    targets no source explains are listed with where their track entered the zone (a gate the scenario
    is missing?). With `register: true` the same spec with the fitted rates is registered as a new
    scenario (201 with `Location`, 202 when it is precomputed as a job, 200 when it was registered
    already) and the answer adds its `id`. See `docs/learning.md`. A detection outside every field of
    view of its step, a track id that jumps further than a target flies, steps whose `step` numbers are
    not consecutive, an unknown sensor type, a sensor on ground its type may not stand on: 422 naming
    the field. A window predicted above `--max-plan-ms` is refused with 422, as a plan is.

    Args:
        id (str):
        body (FitRequest): Body of `POST /v1/scenarios/{id}/fit`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[FitResponse | Problem]
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
    body: FitRequest,
) -> FitResponse | Problem | None:
    """Fit the sources' rates to what the sensors saw

     Estimates each source's Poisson rate from a window of consecutive steps (oldest first, 1 to 500):
    each step's sensors (their looks, at cell centres, as in a plan) and the targets they detected, each
    with a track id that follows it across steps (each target counts once). A source's distinct detected
    targets are Poisson with mean `rate × exposure`, where `exposure` (steps) counts every target in the
    zone during the window that the looks could have detected, those inside at its first step included;
    each detected target is traced back along its velocity to the sources whose position, takeoff cone
    and speeds explain it (shared in proportion to their rates and densities when several do), within
    `tolerance`. The answer is each source's posterior mean `rate` and 95% credible `interval` under a
    Gamma prior (`scenario`: shape 1, mean the spec's rate; `flat`: uniform, Gamma(N + 1, E)); the
    targets no source explains are listed with where their track entered the zone (a gate the scenario
    is missing?). With `register: true` the same spec with the fitted rates is registered as a new
    scenario (201 with `Location`, 202 when it is precomputed as a job, 200 when it was registered
    already) and the answer adds its `id`. See `docs/learning.md`. A detection outside every field of
    view of its step, a track id that jumps further than a target flies, steps whose `step` numbers are
    not consecutive, an unknown sensor type, a sensor on ground its type may not stand on: 422 naming
    the field. A window predicted above `--max-plan-ms` is refused with 422, as a plan is.

    Args:
        id (str):
        body (FitRequest): Body of `POST /v1/scenarios/{id}/fit`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        FitResponse | Problem
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
    body: FitRequest,
) -> Response[FitResponse | Problem]:
    """Fit the sources' rates to what the sensors saw

     Estimates each source's Poisson rate from a window of consecutive steps (oldest first, 1 to 500):
    each step's sensors (their looks, at cell centres, as in a plan) and the targets they detected, each
    with a track id that follows it across steps (each target counts once). A source's distinct detected
    targets are Poisson with mean `rate × exposure`, where `exposure` (steps) counts every target in the
    zone during the window that the looks could have detected, those inside at its first step included;
    each detected target is traced back along its velocity to the sources whose position, takeoff cone
    and speeds explain it (shared in proportion to their rates and densities when several do), within
    `tolerance`. The answer is each source's posterior mean `rate` and 95% credible `interval` under a
    Gamma prior (`scenario`: shape 1, mean the spec's rate; `flat`: uniform, Gamma(N + 1, E)); the
    targets no source explains are listed with where their track entered the zone (a gate the scenario
    is missing?). With `register: true` the same spec with the fitted rates is registered as a new
    scenario (201 with `Location`, 202 when it is precomputed as a job, 200 when it was registered
    already) and the answer adds its `id`. See `docs/learning.md`. A detection outside every field of
    view of its step, a track id that jumps further than a target flies, steps whose `step` numbers are
    not consecutive, an unknown sensor type, a sensor on ground its type may not stand on: 422 naming
    the field. A window predicted above `--max-plan-ms` is refused with 422, as a plan is.

    Args:
        id (str):
        body (FitRequest): Body of `POST /v1/scenarios/{id}/fit`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[FitResponse | Problem]
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
    body: FitRequest,
) -> FitResponse | Problem | None:
    """Fit the sources' rates to what the sensors saw

     Estimates each source's Poisson rate from a window of consecutive steps (oldest first, 1 to 500):
    each step's sensors (their looks, at cell centres, as in a plan) and the targets they detected, each
    with a track id that follows it across steps (each target counts once). A source's distinct detected
    targets are Poisson with mean `rate × exposure`, where `exposure` (steps) counts every target in the
    zone during the window that the looks could have detected, those inside at its first step included;
    each detected target is traced back along its velocity to the sources whose position, takeoff cone
    and speeds explain it (shared in proportion to their rates and densities when several do), within
    `tolerance`. The answer is each source's posterior mean `rate` and 95% credible `interval` under a
    Gamma prior (`scenario`: shape 1, mean the spec's rate; `flat`: uniform, Gamma(N + 1, E)); the
    targets no source explains are listed with where their track entered the zone (a gate the scenario
    is missing?). With `register: true` the same spec with the fitted rates is registered as a new
    scenario (201 with `Location`, 202 when it is precomputed as a job, 200 when it was registered
    already) and the answer adds its `id`. See `docs/learning.md`. A detection outside every field of
    view of its step, a track id that jumps further than a target flies, steps whose `step` numbers are
    not consecutive, an unknown sensor type, a sensor on ground its type may not stand on: 422 naming
    the field. A window predicted above `--max-plan-ms` is refused with 422, as a plan is.

    Args:
        id (str):
        body (FitRequest): Body of `POST /v1/scenarios/{id}/fit`.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        FitResponse | Problem
    """

    return (
        await asyncio_detailed(
            id=id,
            client=client,
            body=body,
        )
    ).parsed
