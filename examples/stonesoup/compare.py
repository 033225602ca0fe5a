#!/usr/bin/env python3
"""Vigil's sensor manager beside Stone Soup's own, on ground truth of Vigil's model.

One Stone Soup run per (platform count, manager): targets from
`VigilGroundTruthSimulator` (the scenario's sources, the same seed for every
manager, starting from the stationary population; targets end at buildings),
N platforms of the type `default` with a `VigilFOVSensor` of the scenario's
coverage (sight lines blocked by the scenario's obstacles) on a
`LatticeActionableMovable` (legal moves: king moves of the sensor's speed
inside the zone, off no-go ground and buildings), and an
ideal tracker (tracks keyed by the detected target's identity, position from
the measurement, velocity from the ground truth; a track is dropped after
16 steps without a detection). Each step: platforms act, sensors measure,
the tracker updates, the manager chooses the next moves, and every move is
checked to be legal. The managers:

  vigil       VigilSensorManager (Vigil's plan: exact estimator, priority
              coordination, the scenario's horizon)
  greedy      GreedySensorManager, reward: expected detections of the
              tracks next step (each platform alone)
  random      RandomSensorManager (seeded, platforms in id order)
  bruteforce  BruteForceSensorManager, the same reward over the joint moves
              (only when the joint action space has at most --brute-limit
              configurations: 9^N for speed-1 sensors)

Reports, per platform count and manager, the mean number of targets
detected per step (by at least one sensor), the targets detected at least
once (of those in the zone during the run) and the mean wall time of one
decision (choose_actions).

    python examples/stonesoup/compare.py --url http://127.0.0.1:8080 \\
        --platforms 2,4,10 --steps 60 --seed 1 --markdown --plot docs/stonesoup-detections.svg
"""

from __future__ import annotations

import argparse
import datetime
import itertools
import math
import random
import sys
import time
from collections.abc import Mapping, Sequence

import numpy as np
from stonesoup.base import Property
from stonesoup.platform.base import Platform
from stonesoup.sensormanager import (
    BruteForceSensorManager,
    GreedySensorManager,
    RandomSensorManager,
)
from stonesoup.sensormanager.reward import RewardFunction
from stonesoup.types.state import GaussianState
from stonesoup.types.track import Track

from vigil_client import Vigil
from vigil_client.stonesoup import (
    VigilFOVSensor,
    VigilGroundTruthSimulator,
    VigilMap,
    VigilSensorManager,
    check_actions,
    make_platform,
)

MANAGERS = ("vigil", "vigil-first", "greedy", "random", "bruteforce")
T0 = datetime.datetime(2026, 1, 1)
STEP = datetime.timedelta(seconds=1)
TRACK_STEPS = 16


class ExpectedDetectionsReward(RewardFunction):
    """Expected detections at ``metric_time`` of the tracks (moved at their
    velocities), by the platforms of the configuration after their moves:
    per track ``1 - prod(1 - p_detect)`` over the platforms' sensors that
    would hold it (in view, and on a clear sight line: ``covers_at``).
    Platforms not in the configuration are ignored."""

    position_mapping: Sequence[int] = Property(default=(0, 2))
    velocity_mapping: Sequence[int] = Property(default=(1, 3))

    def __call__(self, config: Mapping, tracks, metric_time, *args, **kwargs):
        looks = []
        for actionable, actions in config.items():
            if not isinstance(actionable, Platform):
                continue
            moves = [a for a in actions if hasattr(a, "target_value")]
            where = moves[0].target_value if moves else actionable.position
            xy = np.asarray(where, dtype=float).ravel()[:2]
            looks += [(xy, s) for s in actionable.sensors if isinstance(s, VigilFOVSensor)]
        total = 0.0
        for track in tracks:
            sv = np.asarray(track.state_vector, dtype=float).ravel()
            dt = (metric_time - track.timestamp).total_seconds()
            pos = sv[list(self.position_mapping)] + sv[list(self.velocity_mapping)] * dt
            miss = 1.0
            for xy, sensor in looks:
                if sensor.covers_at(xy, pos):
                    miss *= 1.0 - sensor.p_detect
            total += 1.0 - miss
        return total


class SeededRandomSensorManager(RandomSensorManager):
    """Stone Soup's RandomSensorManager, reproducible: its own seeded
    ``random.Random``, and the platforms taken in the order of their ids
    (a set of platforms iterates in a different order in every process)."""

    seed: int = Property(default=0)

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._rng = random.Random(self.seed)

    def choose_actions(self, tracks, timestamp, nchoose=1, **kwargs):
        configs = []
        for _ in range(nchoose):
            config = {}
            for actionable in sorted(self.actionables, key=lambda a: str(a.id)):
                config[actionable] = [self._rng.choice(list(gen))
                                      for gen in actionable.actions(timestamp)]
            configs.append(config)
        return configs


class OrderedBruteForceSensorManager(BruteForceSensorManager):
    """Stone Soup's BruteForceSensorManager with the platforms in the order of
    their ids, so that among joint moves of equal reward the same one wins in
    every run (a set of platforms iterates in a different order in every
    process)."""

    @property
    def actionables(self):
        return sorted(super().actionables, key=lambda a: str(a.id))


class IdealTracker:
    """Tracks keyed by the detected target's identity: position from the
    measurement, velocity from the ground truth; dropped after
    ``max_age`` steps without a detection."""

    def __init__(self, max_age: int):
        self.max_age = max_age
        self.tracks: dict[str, Track] = {}

    def update(self, detections, now: datetime.datetime) -> set[Track]:
        # Several sensors may detect one target: the order is fixed (by id,
        # then measurement) so that the run does not depend on set order.
        def key(d):
            return (d.groundtruth_path.metadata["path_id"],
                    tuple(np.asarray(d.state_vector, dtype=float).ravel()))

        for det in sorted(detections, key=key):
            truth = det.groundtruth_path
            tid = truth.metadata["path_id"]
            sv = np.asarray(truth.state_vector, dtype=float).ravel()
            z = np.asarray(det.state_vector, dtype=float).ravel()
            state = GaussianState([z[0], sv[1], z[1], sv[3]], np.diag([1.0, 0.1, 1.0, 0.1]),
                                  timestamp=now)
            self.tracks.setdefault(tid, Track(id=tid)).append(state)
        limit = self.max_age * STEP
        self.tracks = {k: t for k, t in self.tracks.items() if now - t.timestamp <= limit}
        return set(self.tracks.values())


def grid_starts(vmap: VigilMap, n: int, type_name: str = "default") -> list[tuple[int, int]]:
    """N cells free for ``type_name`` spread over the zone on a near-square
    grid (as vigil-sim's `--start grid`): each at the centre of its share, or
    the nearest free cell."""
    cols = max(1, math.ceil(math.sqrt(n)))
    rows = math.ceil(n / cols)
    free = vmap.free_cells(type_name)
    out = []
    for i in range(n):
        c, r = i % cols, i // cols
        x = (c + 0.5) * vmap.width / cols + vmap.origin[0]
        y = (r + 0.5) * vmap.height / rows + vmap.origin[1]
        cell = vmap.cell_of((x, y))
        if not vmap.is_free(cell, type_name):
            cell = min(free, key=lambda f: (max(abs(f[0] - cell[0]), abs(f[1] - cell[1])), f[1], f[0]))
        out.append(cell)
    return out


def ground_truth(spec: dict, steps: int, seed: int) -> list[tuple[datetime.datetime, list]]:
    """The truth states in the zone at each step (the same for every manager)."""
    sim = VigilGroundTruthSimulator(spec=spec, initial_time=T0, number_steps=steps, seed=seed,
                                    timestep=STEP)
    return [(t, [path[-1] for path in paths]) for t, paths in sim]


def make_manager(name: str, platforms, args, vigil: Vigil, scenario: str):
    reward = ExpectedDetectionsReward()
    common = {"platforms": set(platforms), "take_sensors_from_platforms": False}
    if name in ("vigil", "vigil-first"):
        options = ({"objective": "first_detections", "coordination": "iterated"}
                   if name == "vigil-first" else None)
        return VigilSensorManager(vigil=vigil, scenario_id=scenario, time_step=STEP,
                                  history_steps=TRACK_STEPS, plan_options=options, **common)
    if name == "greedy":
        return GreedySensorManager(reward_function=reward, **common)
    if name == "random":
        return SeededRandomSensorManager(seed=args.seed, **common)
    if name == "bruteforce":
        return OrderedBruteForceSensorManager(reward_function=reward, **common)
    raise ValueError(f"unknown manager {name!r} (known: {', '.join(MANAGERS)})")


def run(name: str, n: int, truth, vmap: VigilMap, args, vigil: Vigil) -> dict:
    """One managed run; returns its per-step detections and summary numbers."""
    platforms = [
        make_platform(f"p{i}", vmap.centre(cell), T0, vmap, time_step=STEP,
                      sensor_kwargs={"seed": args.seed * 1000 + i})
        for i, cell in enumerate(grid_starts(vmap, n))
    ]
    speeds = {p.id: vmap.sensor_type("default").speed for p in platforms}
    manager = make_manager(name, platforms, args, vigil, args.scenario)
    tracker = IdealTracker(TRACK_STEPS)
    per_step, detected, seen, decisions, checked = [], set(), set(), [], 0
    try:
        for k, (now, states) in enumerate(truth):
            if k > 0:
                for p in platforms:
                    p.act(now)
            seen.update(s.metadata["path_id"] for s in states)
            detections = set()
            for p in platforms:
                detections |= p.sensors[0].measure(set(states))
            ids = {d.groundtruth_path.metadata["path_id"] for d in detections}
            per_step.append(len(ids))
            detected |= ids
            tracks = tracker.update(detections, now)
            if k + 1 < len(truth):
                start = time.perf_counter()
                config = manager.choose_actions(tracks, now + STEP)[0]
                decisions.append(time.perf_counter() - start)
                missing = [p.id for p in platforms if not config.get(p)]
                if missing:
                    raise RuntimeError(f"{name}: no action for platforms {missing}")
                # IllegalMoveError on any illegal move of the type.
                check_actions(config, vmap, speeds, types="default")
                checked += len(platforms)
                for actionable, actions in config.items():
                    actionable.add_actions(list(actions))
    finally:
        if isinstance(manager, VigilSensorManager):
            manager.close()
    return {
        "manager": name, "platforms": n, "per_step": per_step,
        "mean": float(np.mean(per_step)), "detected_once": len(detected),
        "targets": len(seen), "moves_checked": checked, "ms": 1000 * float(np.mean(decisions)) if decisions else 0.0,
    }


def markdown(results: list[dict], skipped: list[tuple[int, str]]) -> str:
    lines = ["| platforms | manager | detections per step | targets detected at least once "
             "| ms per decision |", "|---:|---|---:|---:|---:|"]
    for r in results:
        lines.append(f"| {r['platforms']} | `{r['manager']}` | {r['mean']:.2f} | "
                     f"{r['detected_once']} of {r['targets']} | {r['ms']:.1f} |")
    for n, name in skipped:
        lines.append(f"| {n} | `{name}` | — | — | — (joint action space too large) |")
    return "\n".join(lines)


def plot(results: list[dict], path: str, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    matplotlib.rcParams["svg.hashsalt"] = "vigil"
    import matplotlib.pyplot as plt

    counts = sorted({r["platforms"] for r in results})
    fig, axes = plt.subplots(1, len(counts), figsize=(4.2 * len(counts), 3.4), sharey=True,
                             squeeze=False)
    colours = {"vigil": "tab:blue", "vigil-first": "tab:purple", "greedy": "tab:orange",
               "random": "tab:gray", "bruteforce": "tab:green"}
    for ax, n in zip(axes[0], counts, strict=True):
        for r in (r for r in results if r["platforms"] == n):
            ax.plot(range(len(r["per_step"])), r["per_step"], label=r["manager"],
                    color=colours.get(r["manager"]), linewidth=1.2)
        ax.set_title(f"{n} platforms")
        ax.set_xlabel("step")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("targets detected")
    # One legend for every manager that ran (brute force only on small fleets).
    handles = {}
    for ax in axes[0]:
        for line in ax.get_lines():
            handles.setdefault(line.get_label(), line)
    axes[0][-1].legend(handles.values(), handles.keys(), loc="upper right", fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, format="svg", metadata={"Date": None})
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--url", default="http://127.0.0.1:8080", help="a running vigil-server")
    ap.add_argument("--scenario", default="paper-v10", help="a Vigil scenario id")
    ap.add_argument("--platforms", default="2,4,10", help="platform counts, comma-separated")
    ap.add_argument("--steps", type=int, default=60, help="steps per run")
    ap.add_argument("--seed", type=int, default=1, help="seed of targets, detections, random moves")
    ap.add_argument("--managers", default=",".join(MANAGERS), help="managers, comma-separated")
    ap.add_argument("--brute-limit", type=int, default=10_000,
                    help="largest joint action space the brute-force manager is run on")
    ap.add_argument("--plot", metavar="PATH", help="write detections over time as an SVG")
    ap.add_argument("--markdown", action="store_true", help="print the table as Markdown")
    args = ap.parse_args(argv)
    counts = [int(v) for v in args.platforms.split(",")]
    names = [v.strip() for v in args.managers.split(",")]
    for name in names:
        if name not in MANAGERS:
            ap.error(f"unknown manager {name!r} (known: {', '.join(MANAGERS)})")

    with Vigil(args.url) as vigil:
        spec = vigil.get_scenario(args.scenario).spec.to_dict()
        vmap = VigilMap(spec)
        moves = len(vmap.reachable((vmap.cols // 2, vmap.rows // 2), vmap.sensor_type().speed))
        truth = ground_truth(spec, args.steps, args.seed)
        results, skipped = [], []
        for n, name in itertools.product(counts, names):
            if name == "bruteforce" and moves ** n > args.brute_limit:
                skipped.append((n, name))
                continue
            r = run(name, n, truth, vmap, args, vigil)
            results.append(r)
            print(f"{n:3d} platforms {name:10s} {r['mean']:6.2f} detections/step, "
                  f"{r['detected_once']:4d} of {r['targets']} detected at least once, "
                  f"{r['ms']:8.1f} ms/decision", file=sys.stderr, flush=True)
    if args.markdown:
        print(markdown(results, skipped))
    if args.plot:
        plot(results, args.plot,
             f"{args.scenario}: targets detected per step (seed {args.seed}, {args.steps} steps)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
