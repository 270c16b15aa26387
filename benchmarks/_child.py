"""Shared by benchmarks that compare trees: run a Python snippet with another tree's ``src`` on
``PYTHONPATH`` (a fresh process: imports and caches of its own) and read the JSON object it
prints last."""

from __future__ import annotations

import json
import os
import subprocess
import sys


def run_child(src: str, code: str, *argv: str) -> dict:
    """The last stdout line of ``python -c code argv...`` run with ``PYTHONPATH=src``, as JSON."""
    out = subprocess.run(
        [sys.executable, "-c", code, *argv],
        env={**os.environ, "PYTHONPATH": src},
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])
