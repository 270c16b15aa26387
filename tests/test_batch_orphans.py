"""A ``boustro batch`` killed outright (SIGKILL: no ``finally`` runs) leaves no worker behind:
each worker watches the batch's process and exits when it is gone (``worker.exit_with``).
Before, the fork server and both workers stayed, asleep with about 390 MB each, for good."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyogrio.raw
import shapely

SRC = Path(__file__).resolve().parents[1] / "src"


def _children(pid: int) -> list[int]:
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry))
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_workers_exit_when_the_batch_is_killed(tmp_path):
    fields = tmp_path / "fields.gpkg"
    boxes = [
        shapely.box(150_000 + 500 * i, 450_000, 150_400 + 500 * i, 450_300) for i in range(400)
    ]
    pyogrio.raw.write(str(fields), np.array([shapely.to_wkb(b) for b in boxes], dtype=object),
                      [np.array([f"f{i}" for i in range(400)], dtype=object)], ["name"],
                      crs="EPSG:28992", geometry_type="Polygon", driver="GPKG")  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    cmd = [sys.executable, "-m", "boustro", "-q", "batch", str(fields), "--spacing", "2",
           "--workers", "2", "--out", str(tmp_path / "plans.gpkg")]  # fmt: skip
    main = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 240
        while len(workers) < 2 and time.monotonic() < deadline and main.poll() is None:
            time.sleep(0.2)
            workers = [w for child in _children(main.pid) for w in _children(child)]
        assert len(workers) >= 2, "the pool's workers never started"
    finally:
        main.send_signal(signal.SIGKILL)
        main.wait()
    deadline = time.monotonic() + 30
    while any(_alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = [w for w in workers if _alive(w)]
    for w in left:  # leave nothing behind even when the test fails
        os.kill(w, signal.SIGKILL)
    assert not left, f"workers {left} outlived the killed batch"
