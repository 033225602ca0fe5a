"""Schemathesis hooks for Vigil: the one place that lists the rules of the
API that no JSON Schema can state, each with its reason.

The `positive_data_acceptance` check (a request the document calls valid must
not be refused) is replaced by `schema_valid_requests_are_accepted`, which is
the same check except that a 422 whose problem `detail` matches one of the
rules below is accepted: the request was schema-valid but broke a documented
rule that the schema cannot express. `not_a_server_error` is replaced by
`no_server_error_but_retry_later`, which accepts the documented 503s that
say when to retry. Everything else (any other 5xx, a status, content type
or body the document does not describe, a schema-invalid request accepted)
is checked by Schemathesis's own checks.
"""

import re

import schemathesis
from schemathesis.specs.openapi.checks import positive_data_acceptance

# (pattern on the problem's `detail`, why no schema can state the rule).
# Details start with the field's JSON path; `scenario.` prefixes the fields
# of a scenario sent inline to `POST /v1/plan`.
UNSCHEMATISABLE = [
    (
        r"^(scenario\.)?zone\.(width|height): .* is not a whole multiple of cell_size",
        "a relation between two numbers (the zone's extent and the cell size)",
    ),
    (
        r"^(scenario\.)?(zone\.(width|height)|cell_size): (the lattice|.*cells)",
        "a bound on a product of three numbers (width / cell_size × height / cell_size)",
    ),
    (
        r"^(scenario\.)?sources\[\d+\]: \(.*\) is inside the zone",
        "a source's position relative to the zone's extent, given in another field",
    ),
    (
        r"^(scenario\.)?sources\[\d+\]\.heading: (required|.* does not face the zone)",
        "geometry: whether the source is beside one edge, and which half-plane holds the zone",
    ),
    (
        r"^(scenario\.)?sources\[\d+\]: no takeoff direction .* enters the zone",
        "geometry: whether the cone (direction, spread, position) meets the zone",
    ),
    (
        r"^(scenario\.)?sources\[\d+\]\.speeds: the weights' sum must be finite",
        "a bound on a sum of array items",
    ),
    (
        r"^(scenario\.)?sources: too many targets: ",
        "a bound on a sum over the sources' classes of rate × zone diagonal / speed",
    ),
    (
        r"^(scenario\.)?target_speed: required: sources\[\d+\] gives no speeds",
        "required only when some array item lacks a field",
    ),
    (
        r"^(sensors\[\d+\]|history\[\d+\]\[\d+\]): \(.*\) is outside the zone",
        "a position must lie in the zone of the scenario named by the path or body",
    ),
    (
        r"^(sensors\[\d+\]|history\[\d+\]\[\d+\])\.type: unknown sensor type",
        "a name must be one of the sensor types of the scenario named by the path or body",
    ),
    (
        r"^(sensors\[\d+\]|history\[\d+\]\[\d+\]): cell .* is in (a no-go zone|a building)",
        "a position must lie outside the no-go rectangles and (for a ground type) the buildings of the scenario named by the path or body",
    ),
    (
        r"^(scenario\.)?obstacles\[\d+\]\.polygon: ",
        "geometry: a polygon's vertices must be distinct, turn one way, wind once, and meet the zone given in another field",
    ),
    (
        r"^(scenario\.)?sources\[\d+\]: (lies inside a building|every direction of its cone meets a building)",
        "geometry: a source's position and cone against the obstacles, given in another field",
    ),
    (
        r"^estimator: the paper estimator has no notion of sight lines",
        "the paper estimator is refused for a scenario with obstacles, named by the path or body",
    ),
    (
        r"^objective: first_detections needs the exact estimator",
        "a relation between two fields (`objective: first_detections` with `estimator: paper`)",
    ),
    (
        r"^certify: joint coordination ",
        "a relation between two fields (`certify: false` with `coordination: joint`)",
    ),
    (
        r"^(scenario\.)?no_go\[\d+\]: [xy]0 must be < [xy]1",
        "a relation between two numbers (a rectangle's two edges)",
    ),
    (
        r"^(scenario\.)?sensor_types\.default: ",
        "one reserved name among a map's keys (`default` is the top-level fov)",
    ),
    (
        r"^(scenario\.)?sensor_types: .* distinct fields of view on .* cells",
        "a bound on a product (cells × distinct fields of view among the map's values)",
    ),
    (
        r"^sensors\[\d+\]\.id: duplicate sensor id",
        "uniqueness of one property across array items (uniqueItems compares whole items)",
    ),
    (
        r"^this plan is predicted to take .* above this server's limit",
        "a bound on the plan's predicted cost, a function of every field (src/cost.rs)",
    ),
    (
        r"^scenario: its precomputation is predicted to take .* synchronous budget",
        "a bound on the inline scenario's predicted precompute time (src/cost.rs)",
    ),
    (
        r"^paths\[\d+\]\.sensor: (no sensor .* in `sensors`|a second path for sensor)",
        "a path names one of the sensors of another array, each once",
    ),
    (
        r"^paths: sensor .* has no path: give one per sensor",
        "one path for every item of another array (`sensors`)",
    ),
    (
        r"^paths\[\d+\]\.path: must hold the cells of steps 1\.\.=\d+",
        "a path's length is the horizon, given in another field or by the scenario",
    ),
    (
        r"^paths\[\d+\]\.path\[\d+\]: \(col -?\d+, row -?\d+\) (is off the lattice|is in a no-go zone|is in a building|cannot be reached)",
        "a cell must lie on the lattice and outside the no-go zones of the scenario named by the path or body",
    ),
    (
        r"^paths\[\d+\]\.path\[\d+\]: the move from .* is beyond the speed",
        "a move is bounded by the previous cell (or the sensor's own) and its type's speed",
    ),
    (
        r"^steps\[\d+\]\.sensors\[\d+\](: \(.*\) is outside the zone|\.type: unknown sensor type|: cell .* is in (a no-go zone|a building)|\.id: duplicate sensor id)",
        "a fit window's sensors, under the same rules as a plan's sensors (zone, types, ground, unique ids)",
    ),
    (
        r"^steps\[\d+\]\.detections\[\d+\]: \(.*\) lies (outside every field of view|behind an obstacle from every look) of this step",
        "a detection must lie in a field of view of its step: a relation with the sensors of the same step and the scenario's types",
    ),
    (
        r"^steps\[\d+\]\.detections\[\d+\]\.id: track id .* (jumps|is detected twice)",
        "a track id's positions across steps are bounded by the scenario's fastest target; unique within a step",
    ),
    (
        r"^steps\[\d+\]\.step: steps must be consecutive",
        "a relation between items of an array (each step number is the previous one plus one)",
    ),
    (
        r"^learn_rates: a learning session precomputes its scenario again",
        "a bound on the predicted precompute time of the scenario named or sent in the body (src/cost.rs)",
    ),
    (
        r"^detections\[\d+\](\.id: required when the session learns rates|: \(.*\) lies (outside every field of view|behind an obstacle from every look)|\.id: track id .* (jumps|is detected twice))",
        "a learning session's detections: an id (required only when the session, created earlier, learns), in a field of view of the step's sensors, moving no faster than a target",
    ),
    (
        r"^detections: the session would follow \d+ targets",
        "a bound on the session's tracks: this step's detections plus those kept from earlier steps",
    ),
    (
        r"^Idempotency-Key: `.*` named the session's last step, whose body was not this one",
        "a header's value against the session's state: the last step's key comes with that step's body",
    ),
]

_RULES = [re.compile(pattern) for pattern, _ in UNSCHEMATISABLE]


def documented_refusal(detail: str) -> bool:
    """True when a 422's detail is one of the rules above."""
    return any(rule.search(detail) for rule in _RULES)


@schemathesis.check
def schema_valid_requests_are_accepted(ctx, response, case):
    """A schema-valid request is not refused, unless for a rule listed in
    UNSCHEMATISABLE."""
    if response.status_code == 422:
        try:
            detail = response.json().get("detail", "")
        except ValueError:
            detail = ""
        if isinstance(detail, str) and documented_refusal(detail):
            return None
    return positive_data_acceptance(ctx, response, case)


# 503s the document describes, each telling the client when to retry
# (`Retry-After`): shed under load, a scenario still being precomputed by
# its job, a full job queue. They are answers, not server errors.
RETRY_LATER = ("/overloaded", "/scenario-not-ready", "/precompute-queue-full")


@schemathesis.check
def no_server_error_but_retry_later(ctx, response, case):
    """No 5xx, except a documented 503 that says when to retry."""
    if response.status_code < 500:
        return None
    if response.status_code == 503 and "retry-after" in {
        k.lower() for k in response.headers
    }:
        try:
            kind = response.json().get("type", "")
        except ValueError:
            kind = ""
        if isinstance(kind, str) and kind.endswith(RETRY_LATER):
            return None
    raise AssertionError(
        f"Server error: {response.status_code} {response.text[:300]}"
    )
