"""A real `vigil-server` for the tests, started on a free loopback port.

The server binary is `$VIGIL_SERVER` if set, else the workspace's release
build (`target/release/vigil-server`, or under `$CARGO_TARGET_DIR`), which is
built with cargo first when it is missing.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import re
import shutil
import subprocess
import tempfile
import time
from collections.abc import Iterator

import httpx
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
#: The key of the server that requires one (`strict_url`).
API_KEY = "test-key"


def server_binary() -> pathlib.Path:
    if "VIGIL_SERVER" in os.environ:
        return pathlib.Path(os.environ["VIGIL_SERVER"])
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary = target / "release" / "vigil-server"
    if not binary.exists():
        subprocess.run(["cargo", "build", "--release", "--bin", "vigil-server"], cwd=ROOT, check=True)
    return binary


@contextlib.contextmanager
def running_server(*args: str) -> Iterator[str]:
    """Starts a server with `args` and yields its base URL; stops it on exit."""
    data = pathlib.Path(tempfile.mkdtemp(prefix="vigil-pytest-"))
    log = (data / "server.log").open("w+")
    env = {**os.environ, "VIGIL_DATA_DIR": str(data / "store")}
    server = subprocess.Popen(
        [str(server_binary()), "--bind", "127.0.0.1:0", *args], stdout=log, stderr=subprocess.STDOUT, env=env
    )
    try:
        url = None
        deadline = time.monotonic() + 60
        while url is None:
            if server.poll() is not None or time.monotonic() > deadline:
                log.seek(0)
                raise RuntimeError(f"vigil-server did not start:\n{log.read()}")
            log.seek(0)
            found = re.search(r"listening on (127\.0\.0\.1:\d+)", log.read())
            if found:
                url = f"http://{found.group(1)}"
            else:
                time.sleep(0.05)
        httpx.get(f"{url}/healthz", timeout=10).raise_for_status()
        yield url
    finally:
        server.terminate()
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()
        log.close()
        shutil.rmtree(data, ignore_errors=True)


@pytest.fixture(scope="session")
def vigil_url() -> Iterator[str]:
    """A server with the default settings."""
    with running_server() as url:
        yield url


@pytest.fixture(scope="session")
def strict_url() -> Iterator[str]:
    """A server that requires `API_KEY` and precomputes every registered scenario as
    a background job, one at a time, so that 401 and 503 with Retry-After can be
    met on purpose."""
    with running_server("--api-key", API_KEY, "--sync-precompute-ms", "0", "--precompute-jobs", "1") as url:
        yield url
