#!/usr/bin/env python3
"""Time to first plan on a large registered scenario: the replica that
precomputes it against a second replica that loads what the first stored.

Starts two release `vigil-server`s on a fresh database of the PostgreSQL
server at --database (created with `CREATE DATABASE`), registers the
scenario through the first, waits for its first plan and for the stored
row, then starts the second and waits for its first plan. Reports wall time
and each server's CPU time (user + system, from /proc) over those spans.

    cargo build --release --bin vigil-server
    python3 loadtest/precomputed.py --database postgres://vigil@127.0.0.1:5432 --fov square
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
import uuid

TICK = os.sysconf("SC_CLK_TCK")


def cpu_s(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def call(method, url, body=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, method=method,
                                 headers={"content-type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=600) as res:
            return res.status, json.loads(res.read() or b"null")
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read() or b"null")


class Server:
    def __init__(self, binary, url, name):
        self.log = tempfile.NamedTemporaryFile("w+", prefix=f"vigil-{name}-", suffix=".log", delete=False)
        self.proc = subprocess.Popen([binary, "--bind", "127.0.0.1:0", "--database-url", url],
                                     stdout=subprocess.DEVNULL, stderr=self.log)
        deadline = time.time() + 120
        while True:
            text = open(self.log.name).read()
            m = re.search(r"listening on (\S+)", text)
            if m:
                self.base = f"http://{m.group(1)}"
                return
            if self.proc.poll() is not None or time.time() > deadline:
                sys.exit(f"{name} did not start:\n{text}")
            time.sleep(0.02)

    def text(self):
        return open(self.log.name).read()

    def stop(self):
        self.proc.terminate()
        self.proc.wait()


def first_plan(server, sid):
    body = {"sensors": [{"id": "a", "x": 1000.5, "y": 1000.5}], "horizon": 3}
    while True:
        status, out = call("POST", f"{server.base}/v1/scenarios/{sid}/plan", body)
        if status == 200:
            return
        if status != 503:
            sys.exit(f"plan: {status} {out}")
        time.sleep(0.01)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--database", required=True, help="server URL, without a database name")
    ap.add_argument("--fov", choices=["square", "circle"], default="square")
    ap.add_argument("--binary", default="target/release/vigil-server")
    a = ap.parse_args()
    name = f"precomputed_{uuid.uuid4().hex[:8]}"
    subprocess.run(["psql", f"{a.database}/postgres", "-qc", f"CREATE DATABASE {name}"], check=True)
    url = f"{a.database}/{name}"
    fov = {"shape": "square", "half_width": 2.5} if a.fov == "square" else {"shape": "circle", "radius": 40}
    spec = {"zone": {"width": 2000, "height": 2000}, "cell_size": 1, "fov": fov, "target_speed": 10,
            "sources": [{"x": -1, "y": 1000, "rate": 0.5}, {"x": 2001, "y": 1000, "rate": 0.5}]}

    first = Server(a.binary, url, "first")
    c0, t0 = cpu_s(first.proc.pid), time.time()
    status, out = call("POST", f"{first.base}/v1/scenarios", spec)
    assert status in (201, 202), out
    sid = out["id"]
    first_plan(first, sid)
    t_first, c_first = time.time() - t0, cpu_s(first.proc.pid) - c0
    while "stored a precomputation" not in first.text():
        time.sleep(0.05)
    stored = re.search(r"stored a precomputation.*", first.text()).group(0)

    second = Server(a.binary, url, "second")
    c0, t0 = cpu_s(second.proc.pid), time.time()
    first_plan(second, sid)
    t_second, c_second = time.time() - t0, cpu_s(second.proc.pid) - c0
    loaded = re.search(r"loaded a stored precomputation.*", second.text())
    for s in (first, second):
        s.stop()
    print(json.dumps({
        "fov": a.fov, "cells": 4_000_000,
        "first": {"wall_s": round(t_first, 3), "cpu_s": round(c_first, 3)},
        "second": {"wall_s": round(t_second, 3), "cpu_s": round(c_second, 3)},
        "wall_ratio": round(t_second / t_first, 4), "cpu_ratio": round(c_second / c_first, 4),
        "stored": stored, "loaded": loaded.group(0) if loaded else None,
    }, indent=1))


if __name__ == "__main__":
    main()
