#!/usr/bin/env python3
"""An external simulator that asks Vigil where its sensors should go.

Standard library only. It registers a scenario (POST /v1/scenarios), then
runs 50 steps of a simple world of its own: targets enter from two sources
outside a 200 x 100 zone and fly straight; three sensors see a 30 x 30
square around them. Each step it reports the sensors, the targets they see
now (with their velocities) and the sensors' recent positions, asks for a
plan (POST /v1/scenarios/{id}/plan), moves every sensor to the first cell of
its path, moves the targets, and prints what the sensors detect.

    python3 examples/python/drive.py [URL] [--steps N] [--seed S]

URL is a running vigil-server, http://127.0.0.1:8080 by default.
"""

import argparse
import json
import math
import random
import sys
import urllib.error
import urllib.request

SCENARIO = {
    "name": "python example",
    "zone": {"width": 200, "height": 100},
    "cell_size": 10,
    "fov": {"shape": "square", "half_width": 15},
    "target_speed": 6,
    "horizon": 3,
    "sources": [
        {"x": -1, "y": 50, "rate": 0.5, "heading": "east"},
        {"x": 100, "y": 101, "rate": 0.3, "heading": "south"},
    ],
}
HEADINGS = {"east": 0.0, "north": math.pi / 2, "west": math.pi, "south": -math.pi / 2}
HISTORY = 8


def call(method, url, body=None):
    """Sends JSON, returns the decoded JSON answer; exits on an HTTP error."""
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, method=method,
                                 headers={"content-type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=30) as resp:
            return json.load(resp)
    except urllib.error.HTTPError as e:
        sys.exit(f"{method} {url}: {e.code} {e.read().decode(errors='replace')}")
    except urllib.error.URLError as e:
        sys.exit(f"{method} {url}: {e.reason} (is vigil-server running?)")


def poisson(rng, rate):
    """A Poisson(rate) count (Knuth's method; rates here are small)."""
    limit, k, p = math.exp(-rate), 0, rng.random()
    while p > limit:
        k += 1
        p *= rng.random()
    return k


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("url", nargs="?", default="http://127.0.0.1:8080")
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    base = args.url.rstrip("/")
    rng = random.Random(args.seed)

    scenario = call("POST", f"{base}/v1/scenarios", SCENARIO)
    sid = scenario["id"]
    width, height = SCENARIO["zone"]["width"], SCENARIO["zone"]["height"]
    half, speed = SCENARIO["fov"]["half_width"], SCENARIO["target_speed"]
    print(f"scenario {sid}: {width}x{height}, "
          f"{scenario['summary']['expected_targets_in_zone']:.1f} targets in the zone on average")

    sensors = [(35.0, 45.0), (105.0, 55.0), (165.0, 45.0)]  # cell centres
    history = []  # the sensors' positions 1, 2, ... steps ago
    targets = []  # [id, x, y, vx, vy]
    next_id, total, expected = 0, 0, 0.0

    def in_zone(x, y):
        return 0 <= x <= width and 0 <= y <= height

    def seen(x, y):
        return in_zone(x, y) and any(abs(x - sx) <= half and abs(y - sy) <= half
                                     for sx, sy in sensors)

    for step in range(1, args.steps + 1):
        # Ask for a plan: the sensors, the targets they see now, the history.
        body = {
            "sensors": [{"id": i, "x": x, "y": y} for i, (x, y) in enumerate(sensors)],
            "targets": [{"id": t[0], "x": t[1], "y": t[2], "vx": t[3], "vy": t[4]}
                        for t in targets if seen(t[1], t[2])],
        }
        if history:
            body["history"] = [[{"x": x, "y": y} for x, y in past] for past in history]
        plan = call("POST", f"{base}/v1/scenarios/{sid}/plan", body)
        expected += plan["expected_by_step"][0]
        history = ([list(sensors)] + history)[:HISTORY]
        sensors = [(p["path"][0]["x"], p["path"][0]["y"]) for p in plan["plans"]]

        # The world moves: targets fly, new ones take off from the sources.
        targets = [[i, x + vx, y + vy, vx, vy] for i, x, y, vx, vy in targets]
        for src in SCENARIO["sources"]:
            for _ in range(poisson(rng, src["rate"])):
                a = HEADINGS[src["heading"]] + rng.uniform(-math.pi / 2, math.pi / 2)
                vx, vy = speed * math.cos(a), speed * math.sin(a)
                targets.append([next_id, src["x"] + vx, src["y"] + vy, vx, vy])
                next_id += 1
        # Gone once they are out of the zone and flying away from it.
        targets = [t for t in targets if in_zone(t[1], t[2])
                   or math.hypot(t[1] - width / 2, t[2] - height / 2)
                   < math.hypot(width, height)]

        inside = [t for t in targets if in_zone(t[1], t[2])]
        detected = [t for t in inside if seen(t[1], t[2])]
        total += len(detected)
        where = ", ".join(f"#{t[0]} ({t[1]:.0f},{t[2]:.0f})" for t in detected)
        print(f"step {step:2}: detected {len(detected)} of {len(inside)} in the zone"
              + (f": {where}" if where else ""))

    print(f"done: {args.steps} steps, {total} detections, "
          f"{total / args.steps:.2f} per step (the plans expected {expected / args.steps:.2f})")


if __name__ == "__main__":
    main()
