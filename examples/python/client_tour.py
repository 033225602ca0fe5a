#!/usr/bin/env python3
"""A tour of Vigil's Python package (`pip install ./clients/python`).

It plans for two sensors in the built-in `paper-v10`, registers a scenario
of its own, drives three sensors through it for a few steps in a session
(moving each to the first cell of its plan), and shows what an error looks
like.

    python3 examples/python/client_tour.py [URL] [--steps N]

URL is a running vigil-server, http://127.0.0.1:8080 by default.
"""

import argparse

from vigil_client import Vigil, VigilError

SCENARIO = {
    "name": "python tour",
    "zone": {"width": 200, "height": 100},
    "cell_size": 10,
    "fov": {"shape": "square", "half_width": 15},
    "target_speed": 6,
    "sources": [
        {"x": -1, "y": 50, "rate": 0.5, "heading": "east"},
        {"x": 100, "y": 101, "rate": 0.3, "heading": "south"},
    ],
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("url", nargs="?", default="http://127.0.0.1:8080")
    ap.add_argument("--steps", type=int, default=5)
    args = ap.parse_args()

    with Vigil(args.url) as vigil:
        # One plan, stateless.
        plan = vigil.plan("paper-v10", {"sensors": [{"id": "a", "x": 55, "y": 55}, {"id": "b", "x": 245, "y": 245}]})
        for p in plan.plans:
            print(f"sensor {p.sensor}: {[(c.x, c.y) for c in p.path]}, expects {p.expected_detections:.3f}")
        print(f"together {plan.expected_detections:.3f}, certified within {plan.bound.gap:.2%} of the best joint plan")

        # A scenario of our own, and a session that keeps the history.
        scenario = vigil.create_scenario(SCENARIO)
        sensors = [{"id": i, "x": x, "y": 45} for i, x in enumerate((35, 105, 165))]
        with vigil.session(scenario.id, horizon=3) as session:
            for _ in range(args.steps):
                step = session.step({"sensors": sensors})
                sensors = [{"id": p.sensor, "x": p.path[0].x, "y": p.path[0].y} for p in step.plans]
                print(f"step {step.step}: expects {step.expected_by_step[0]:.3f} now, moves to "
                      + ", ".join(f"({s['x']:.0f},{s['y']:.0f})" for s in sensors))

        # Errors carry the server's problem+json.
        try:
            vigil.plan(scenario.id, {"sensors": [{"id": "a", "x": 500, "y": 50}]})
        except VigilError as error:
            print(f"refused: {error.status} {error.title}: {error.detail}")
        vigil.delete_scenario(scenario.id)


if __name__ == "__main__":
    main()
