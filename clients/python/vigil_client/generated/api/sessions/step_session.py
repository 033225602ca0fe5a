from http import HTTPStatus
from typing import Any
from urllib.parse import quote

import httpx

from ...client import AuthenticatedClient, Client
from ...types import Response, UNSET
from ... import errors

from ...models.problem import Problem
from ...models.step_request import StepRequest
from ...models.step_response import StepResponse
from ...types import Unset


def _get_kwargs(
    id: str,
    *,
    body: StepRequest,
    idempotency_key: None | str | Unset = UNSET,
) -> dict[str, Any]:
    headers: dict[str, Any] = {}
    if not isinstance(idempotency_key, Unset):
        headers["Idempotency-Key"] = idempotency_key

    _kwargs: dict[str, Any] = {
        "method": "post",
        "url": "/v1/sessions/{id}/step".format(
            id=quote(str(id), safe=""),
        ),
    }

    _kwargs["json"] = body.to_dict()

    headers["Content-Type"] = "application/json"

    _kwargs["headers"] = headers
    return _kwargs


def _parse_response(
    *, client: AuthenticatedClient | Client, response: httpx.Response
) -> Problem | StepResponse | None:
    if response.status_code == 200:
        response_200 = StepResponse.from_dict(response.json())

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

    if response.status_code == 409:
        response_409 = Problem.from_dict(response.json())

        return response_409

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
) -> Response[Problem | StepResponse]:
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
    body: StepRequest,
    idempotency_key: None | str | Unset = UNSET,
) -> Response[Problem | StepResponse]:
    """Plan the next step of a session

     Records this step and plans from the session's state. The session moves every track one step along
    its straight line, takes each detection as its track's new state (matched by `id`, else by position
    and velocity, else a new track), drops the tracks that left the zone or were not detected for
    `history_steps` steps, and plans from the sensors now, the tracks and the sensors' positions over
    the last `history_steps` steps: the same plan as the stateless request of that state. Only a step
    whose plan is made is recorded, so a step that failed (4xx, 5xx) may be sent again. Steps of one
    session run one at a time, each from the state the one before left, whichever replica serves them. A
    step sent with an `Idempotency-Key` header is answered, to the byte, with the first answer to that
    key if the session's last step had it and the same body (the same JSON values, whatever their
    layout), and is not made again: send one to retry safely after a lost answer, a timeout or a 503.
    The last step's key with another body is refused with 422 (`idempotency-key-reused`). Rules no
    schema can state (each a 422 whose `detail` names the field): every sensor and history position lies
    in the scenario's zone, and sensor ids are unique; no ground sensor (a type not `elevated`), now or
    in the history, stands on a cell whose centre lies in a building; and with obstacles the estimator
    is `exact`.

    Args:
        id (str):
        idempotency_key (None | str | Unset):
        body (StepRequest): Body of a session's step.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[Problem | StepResponse]
    """

    kwargs = _get_kwargs(
        id=id,
        body=body,
        idempotency_key=idempotency_key,
    )

    response = client.get_httpx_client().request(
        **kwargs,
    )

    return _build_response(client=client, response=response)


def sync(
    id: str,
    *,
    client: AuthenticatedClient,
    body: StepRequest,
    idempotency_key: None | str | Unset = UNSET,
) -> Problem | StepResponse | None:
    """Plan the next step of a session

     Records this step and plans from the session's state. The session moves every track one step along
    its straight line, takes each detection as its track's new state (matched by `id`, else by position
    and velocity, else a new track), drops the tracks that left the zone or were not detected for
    `history_steps` steps, and plans from the sensors now, the tracks and the sensors' positions over
    the last `history_steps` steps: the same plan as the stateless request of that state. Only a step
    whose plan is made is recorded, so a step that failed (4xx, 5xx) may be sent again. Steps of one
    session run one at a time, each from the state the one before left, whichever replica serves them. A
    step sent with an `Idempotency-Key` header is answered, to the byte, with the first answer to that
    key if the session's last step had it and the same body (the same JSON values, whatever their
    layout), and is not made again: send one to retry safely after a lost answer, a timeout or a 503.
    The last step's key with another body is refused with 422 (`idempotency-key-reused`). Rules no
    schema can state (each a 422 whose `detail` names the field): every sensor and history position lies
    in the scenario's zone, and sensor ids are unique; no ground sensor (a type not `elevated`), now or
    in the history, stands on a cell whose centre lies in a building; and with obstacles the estimator
    is `exact`.

    Args:
        id (str):
        idempotency_key (None | str | Unset):
        body (StepRequest): Body of a session's step.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Problem | StepResponse
    """

    return sync_detailed(
        id=id,
        client=client,
        body=body,
        idempotency_key=idempotency_key,
    ).parsed


async def asyncio_detailed(
    id: str,
    *,
    client: AuthenticatedClient,
    body: StepRequest,
    idempotency_key: None | str | Unset = UNSET,
) -> Response[Problem | StepResponse]:
    """Plan the next step of a session

     Records this step and plans from the session's state. The session moves every track one step along
    its straight line, takes each detection as its track's new state (matched by `id`, else by position
    and velocity, else a new track), drops the tracks that left the zone or were not detected for
    `history_steps` steps, and plans from the sensors now, the tracks and the sensors' positions over
    the last `history_steps` steps: the same plan as the stateless request of that state. Only a step
    whose plan is made is recorded, so a step that failed (4xx, 5xx) may be sent again. Steps of one
    session run one at a time, each from the state the one before left, whichever replica serves them. A
    step sent with an `Idempotency-Key` header is answered, to the byte, with the first answer to that
    key if the session's last step had it and the same body (the same JSON values, whatever their
    layout), and is not made again: send one to retry safely after a lost answer, a timeout or a 503.
    The last step's key with another body is refused with 422 (`idempotency-key-reused`). Rules no
    schema can state (each a 422 whose `detail` names the field): every sensor and history position lies
    in the scenario's zone, and sensor ids are unique; no ground sensor (a type not `elevated`), now or
    in the history, stands on a cell whose centre lies in a building; and with obstacles the estimator
    is `exact`.

    Args:
        id (str):
        idempotency_key (None | str | Unset):
        body (StepRequest): Body of a session's step.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Response[Problem | StepResponse]
    """

    kwargs = _get_kwargs(
        id=id,
        body=body,
        idempotency_key=idempotency_key,
    )

    response = await client.get_async_httpx_client().request(**kwargs)

    return _build_response(client=client, response=response)


async def asyncio(
    id: str,
    *,
    client: AuthenticatedClient,
    body: StepRequest,
    idempotency_key: None | str | Unset = UNSET,
) -> Problem | StepResponse | None:
    """Plan the next step of a session

     Records this step and plans from the session's state. The session moves every track one step along
    its straight line, takes each detection as its track's new state (matched by `id`, else by position
    and velocity, else a new track), drops the tracks that left the zone or were not detected for
    `history_steps` steps, and plans from the sensors now, the tracks and the sensors' positions over
    the last `history_steps` steps: the same plan as the stateless request of that state. Only a step
    whose plan is made is recorded, so a step that failed (4xx, 5xx) may be sent again. Steps of one
    session run one at a time, each from the state the one before left, whichever replica serves them. A
    step sent with an `Idempotency-Key` header is answered, to the byte, with the first answer to that
    key if the session's last step had it and the same body (the same JSON values, whatever their
    layout), and is not made again: send one to retry safely after a lost answer, a timeout or a 503.
    The last step's key with another body is refused with 422 (`idempotency-key-reused`). Rules no
    schema can state (each a 422 whose `detail` names the field): every sensor and history position lies
    in the scenario's zone, and sensor ids are unique; no ground sensor (a type not `elevated`), now or
    in the history, stands on a cell whose centre lies in a building; and with obstacles the estimator
    is `exact`.

    Args:
        id (str):
        idempotency_key (None | str | Unset):
        body (StepRequest): Body of a session's step.

    Raises:
        errors.UnexpectedStatus: If the server returns an undocumented status code and Client.raise_on_unexpected_status is True.
        httpx.TimeoutException: If the request takes longer than Client.timeout.

    Returns:
        Problem | StepResponse
    """

    return (
        await asyncio_detailed(
            id=id,
            client=client,
            body=body,
            idempotency_key=idempotency_key,
        )
    ).parsed
