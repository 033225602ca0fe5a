#!/usr/bin/env python3
"""Runs every command the READMEs and the pages under docs/ show, in a form that ends quickly, so a
command that does not run as written on a fresh clone fails CI.

Commands are the `cargo …` and `bash …` lines of ```sh blocks and the
inline code spans that start with them (an environment prefix such as
`SLO_MS=5` is allowed). Each is run as:
- `cargo run ARGS [-- REST]`   → `cargo run ARGS -- --help` (an example is
  built instead: examples take no --help);
- `cargo bench ARGS [-- REST]` → `cargo bench ARGS --no-run`;
- `cargo test ARGS [FILTER]`   → `cargo test ARGS --no-run`;
- `cargo build ARGS`           → as written;
- `bash FILE`                  → the file exists and parses (`bash -n`).
"""

import pathlib
import re
import shlex
import subprocess
import sys

FILES = ["README.md", "loadtest/README.md", "sim/README.md", "clients/python/README.md"]
START = re.compile(r"^(?:[A-Z_]+=\S*\s+)*(cargo|bash)\s")


def shown(text: str) -> list[str]:
    found = []
    for block in re.findall(r"```sh\n(.*?)```", text, re.S):
        for line in block.splitlines():
            line = line.strip()
            if START.match(line):
                found.append(line.split(" #", 1)[0].strip())
    # Inline spans, once the fenced blocks are out of the way.
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    for span in re.findall(r"`([^`]+)`", prose):
        span = " ".join(span.split())
        # A span with an ellipsis names a kind of command, not one to run.
        if START.match(span) and "…" not in span:
            found.append(span)
    return found


def runnable(command: str) -> list[str]:
    words = shlex.split(command)
    while "=" in words[0] and not words[0].startswith("-"):
        words = words[1:]
    if words[0] == "bash":
        return ["bash", "-n", words[1]]
    sub = words[1]
    head = words[: words.index("--")] if "--" in words else words
    if sub == "run":
        if "--example" in head:
            return ["cargo", "build", *head[2:]]
        return [*head, "--", "--help"]
    if sub == "bench":
        return [*head, "--no-run"]
    if sub == "test":
        return [*head, "--no-run"]
    return head


def main() -> int:
    root = pathlib.Path(__file__).resolve().parent.parent
    commands = []
    pages = sorted(str(p.relative_to(root)) for p in (root / "docs").glob("*.md"))
    for name in [*FILES, *pages]:
        for command in shown((root / name).read_text()):
            if command not in commands:
                commands.append(command)
    failed = []
    ran = {}
    for command in commands:
        argv = runnable(command)
        print(f"README: {command}\n  runs as: {shlex.join(argv)}", flush=True)
        key = tuple(argv)
        if key not in ran:
            done = subprocess.run(argv, cwd=root, stdout=subprocess.DEVNULL, timeout=1800)
            ran[key] = done.returncode == 0
        if not ran[key]:
            failed.append(command)
    if failed:
        print("README commands that do not run as written:", *failed, sep="\n  ")
        return 1
    print(f"README: all {len(commands)} commands run as written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
