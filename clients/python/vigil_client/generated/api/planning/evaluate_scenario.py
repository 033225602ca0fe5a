from http import HTTPStatus
from typing import Any
from urllib.parse import quote

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response
from ... import errors

from ...models.evaluate_body import EvaluateBody
from ...models.evaluate_response import EvaluateResponse
from ...models.problem import Problem


def _get_kwargs(
    id: str,
    *,
    body: EvaluateBody,
) -> dict[str, Any]:
    headers: dict[str, Any] = {}

    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/scenarios/{id}/evaluate".format(
            id=quote(str(id), safe=""),
        ),
    }

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
    id: str,
    *,
    client: AuthenticatedClient,
    body: EvaluateBody,
) -> Response[EvaluateResponse | Problem]:
    """Score given paths of the sensors

     Scores one path per sensor, whoever planned it: the expected number of distinct targets detected
    over steps 1..T (the total a plan reports as `expected_detections`, and per step), each sensor's
    marginal (what the total loses without its path) and the breaches of the minimum separation, with
    the requested estimator. The body is a plan request (its `coordination`, `explain`, `gap_target`,
    `budget_ms` and `certify` are checked as a plan checks them, so a plan's body scores as sent, and
    play no part) plus `paths`. A plan's own paths score its `expected_detections`. With the `paper`
    estimator, whose total depends on the order, the paths count in the order given, the first as the
    highest priority. Rules no schema can state (each a 422 whose `detail` names the field): every
    sensor and history position lies in the scenario's zone, and sensor ids are unique; no ground sensor
    (a type not `elevated`), now or in the history, stands on a cell whose centre lies in a building;
    and with obstacles the estimator is `exact`. The paths' rules (each a 422 whose `detail` names the
    field): one path per sensor, each naming a sensor of `sensors` once, of exactly T cells (the
    horizon's steps 1..T), every cell on the lattice and outside the no-go zones (and, for a ground
    sensor, outside the buildings), each step a move of at most the sensor type's speed (king moves)
    that free cells allow, from the sensor's own cell.

    Args:
        id (str):
        body (EvaluateBody): Body of `POST /v1/scenarios/{id}/evaluate`: a plan request's fields
            (its `coordination`, `explain`, `gap_target`, `budget_ms` and
            `certify` are checked as a plan checks them, so a plan's body
            scores as sent, and play no part) and the paths to score.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[EvaluateResponse | Problem]
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
    body: EvaluateBody,
) -> EvaluateResponse | Problem | None:
    """Score given paths of the sensors

     Scores one path per sensor, whoever planned it: the expected number of distinct targets detected
    over steps 1..T (the total a plan reports as `expected_detections`, and per step), each sensor's
    marginal (what the total loses without its path) and the breaches of the minimum separation, with
    the requested estimator. The body is a plan request (its `coordination`, `explain`, `gap_target`,
    `budget_ms` and `certify` are checked as a plan checks them, so a plan's body scores as sent, and
    play no part) plus `paths`. A plan's own paths score its `expected_detections`. With the `paper`
    estimator, whose total depends on the order, the paths count in the order given, the first as the
    highest priority. Rules no schema can state (each a 422 whose `detail` names the field): every
    sensor and history position lies in the scenario's zone, and sensor ids are unique; no ground sensor
    (a type not `elevated`), now or in the history, stands on a cell whose centre lies in a building;
    and with obstacles the estimator is `exact`. The paths' rules (each a 422 whose `detail` names the
    field): one path per sensor, each naming a sensor of `sensors` once, of exactly T cells (the
    horizon's steps 1..T), every cell on the lattice and outside the no-go zones (and, for a ground
    sensor, outside the buildings), each step a move of at most the sensor type's speed (king moves)
    that free cells allow, from the sensor's own cell.

    Args:
        id (str):
        body (EvaluateBody): Body of `POST /v1/scenarios/{id}/evaluate`: a plan request's fields
            (its `coordination`, `explain`, `gap_target`, `budget_ms` and
            `certify` are checked as a plan checks them, so a plan's body
            scores as sent, and play no part) and the paths to score.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        EvaluateResponse | Problem
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
    body: EvaluateBody,
) -> Response[EvaluateResponse | Problem]:
    """Score given paths of the sensors

     Scores one path per sensor, whoever planned it: the expected number of distinct targets detected
    over steps 1..T (the total a plan reports as `expected_detections`, and per step), each sensor's
    marginal (what the total loses without its path) and the breaches of the minimum separation, with
    the requested estimator. The body is a plan request (its `coordination`, `explain`, `gap_target`,
    `budget_ms` and `certify` are checked as a plan checks them, so a plan's body scores as sent, and
    play no part) plus `paths`. A plan's own paths score its `expected_detections`. With the `paper`
    estimator, whose total depends on the order, the paths count in the order given, the first as the
    highest priority. Rules no schema can state (each a 422 whose `detail` names the field): every
    sensor and history position lies in the scenario's zone, and sensor ids are unique; no ground sensor
    (a type not `elevated`), now or in the history, stands on a cell whose centre lies in a building;
    and with obstacles the estimator is `exact`. The paths' rules (each a 422 whose `detail` names the
    field): one path per sensor, each naming a sensor of `sensors` once, of exactly T cells (the
    horizon's steps 1..T), every cell on the lattice and outside the no-go zones (and, for a ground
    sensor, outside the buildings), each step a move of at most the sensor type's speed (king moves)
    that free cells allow, from the sensor's own cell.

    Args:
        id (str):
        body (EvaluateBody): Body of `POST /v1/scenarios/{id}/evaluate`: a plan request's fields
            (its `coordination`, `explain`, `gap_target`, `budget_ms` and
            `certify` are checked as a plan checks them, so a plan's body
            scores as sent, and play no part) and the paths to score.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[EvaluateResponse | Problem]
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
    body: EvaluateBody,
) -> EvaluateResponse | Problem | None:
    """Score given paths of the sensors

     Scores one path per sensor, whoever planned it: the expected number of distinct targets detected
    over steps 1..T (the total a plan reports as `expected_detections`, and per step), each sensor's
    marginal (what the total loses without its path) and the breaches of the minimum separation, with
    the requested estimator. The body is a plan request (its `coordination`, `explain`, `gap_target`,
    `budget_ms` and `certify` are checked as a plan checks them, so a plan's body scores as sent, and
    play no part) plus `paths`. A plan's own paths score its `expected_detections`. With the `paper`
    estimator, whose total depends on the order, the paths count in the order given, the first as the
    highest priority. Rules no schema can state (each a 422 whose `detail` names the field): every
    sensor and history position lies in the scenario's zone, and sensor ids are unique; no ground sensor
    (a type not `elevated`), now or in the history, stands on a cell whose centre lies in a building;
    and with obstacles the estimator is `exact`. The paths' rules (each a 422 whose `detail` names the
    field): one path per sensor, each naming a sensor of `sensors` once, of exactly T cells (the
    horizon's steps 1..T), every cell on the lattice and outside the no-go zones (and, for a ground
    sensor, outside the buildings), each step a move of at most the sensor type's speed (king moves)
    that free cells allow, from the sensor's own cell.

    Args:
        id (str):
        body (EvaluateBody): Body of `POST /v1/scenarios/{id}/evaluate`: a plan request's fields
            (its `coordination`, `explain`, `gap_target`, `budget_ms` and
            `certify` are checked as a plan checks them, so a plan's body
            scores as sent, and play no part) and the paths to score.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        EvaluateResponse | Problem
    """

    return (
        await asyncio_detailed(
            id=id,
            client=client,
            body=body,
        )
    ).parsed
