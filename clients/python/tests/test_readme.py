"""The Python the READMEs show runs as written, in order, against a real server."""

from __future__ import annotations

import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
PAGES = ["clients/python/README.md", "README.md", "docs/stonesoup.md"]


def blocks(page: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", (ROOT / page).read_text(), re.S)


@pytest.mark.parametrize("page", PAGES)
def test_python_blocks_run(page: str, vigil_url: str) -> None:
    code = blocks(page)
    assert code, f"{page} shows no Python"
    namespace: dict[str, object] = {}
    for block in code:
        # The pages show the default address, and one of a deployed server.
        block = block.replace("http://127.0.0.1:8080", vigil_url).replace("http://vigil.internal:8080", vigil_url)
        block = block.replace("AsyncVigil()", f"AsyncVigil({vigil_url!r})")
        exec(compile(block, page, "exec"), namespace)  # noqa: S102
