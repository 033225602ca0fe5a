#!/usr/bin/env python3
"""Registration latency: POSTs COUNT distinct small scenarios to
/v1/scenarios one after another over one kept-alive connection, and prints
the latency percentiles of the 201s (standard library only).

    python3 loadtest/registration.py --url http://127.0.0.1:8080 --count 300

Each spec differs from the others by one source's rate, so each is a new
registration (201): precomputation (a 10×10 lattice, well under 1 ms) plus
the store's durable write (a file and two fsyncs, or a database row).
"""
import argparse
import http.client
import json
import statistics
import sys
import time
import urllib.parse


def spec(n: int, salt: int) -> dict:
    return {
        "name": f"reg-{salt}-{n}",
        "zone": {"width": 100, "height": 100}, "cell_size": 10,
        "fov": {"shape": "square", "half_width": 15}, "target_speed": 6,
        "sources": [{"x": -1, "y": 50, "rate": 0.001 * (n + 1)},
                    {"x": 50, "y": 101, "rate": 0.2}],
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--url", default="http://127.0.0.1:8080")
    p.add_argument("--count", type=int, default=300)
    p.add_argument("--warmup", type=int, default=20)
    a = p.parse_args()
    url = urllib.parse.urlparse(a.url)
    conn = http.client.HTTPConnection(url.hostname, url.port or 80, timeout=30)
    salt = time.time_ns()
    ms = []
    for n in range(a.warmup + a.count):
        body = json.dumps(spec(n, salt))
        t = time.perf_counter()
        conn.request("POST", "/v1/scenarios", body, {"content-type": "application/json"})
        res = conn.getresponse()
        res.read()
        took = (time.perf_counter() - t) * 1e3
        if res.status != 201:
            print(f"unexpected {res.status}", file=sys.stderr)
            return 1
        if n >= a.warmup:
            ms.append(took)
    ms.sort()
    q = lambda f: ms[min(len(ms) - 1, int(f * len(ms)))]
    print(json.dumps({
        "registrations": len(ms), "p50_ms": round(q(0.5), 2), "p90_ms": round(q(0.9), 2),
        "p99_ms": round(q(0.99), 2), "mean_ms": round(statistics.fmean(ms), 2),
        "max_ms": round(ms[-1], 2)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
