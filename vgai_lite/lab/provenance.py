"""Where a record came from: the command, the code, the machine and its load, the checkpoint flown.

Every training and evaluation record in ``data/`` carries a ``provenance`` entry, so that "trained
alone on the two cores" is measured, not typed, and a record can be checked against its checkpoint:

    with Provenance(command="python -m vgai_lite evaluate ...") as prov:
        result = relative_cost(...)
    record["provenance"] = prov.record(checkpoint=path, seed=seed, episodes=50)

``record`` holds: the command that reruns it, the git commit and whether the library (``vgai_lite/``)
had uncommitted changes, Python and torch versions, torch's thread count, the sha256 of the
checkpoint, the episodes' seed and count, the wall time, and the machine's 1-minute load average
sampled every ``interval`` seconds while the run lasted (its mean and max: a load near the thread
count means the run had the machine to itself; near twice that, it shared it).
"""

from __future__ import annotations

import hashlib
import os
import platform
import subprocess
import threading
import time
from pathlib import Path
from typing import Optional, Union

import torch

from ..book import ROOT


def sha256(path: Union[str, Path]) -> str:
    """The sha256 of a file's bytes (a checkpoint's identity; its first 12 digits key the robustness
    sweep's cells)."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def repo_relative(path: Union[str, Path]) -> str:
    """``path`` relative to the repository (as records name files), or as given when outside it."""
    p = Path(path).resolve()
    return str(p.relative_to(ROOT)) if p.is_relative_to(ROOT) else str(path)


def git_state() -> tuple[Optional[str], Optional[bool]]:
    """(commit, whether vgai_lite/ differs from it), or (None, None) outside a git checkout."""
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                                check=True).stdout.strip()
        dirty = bool(subprocess.run(["git", "status", "--porcelain", "--", "vgai_lite"], cwd=ROOT,
                                    capture_output=True, text=True, check=True).stdout.strip())
    except (OSError, subprocess.CalledProcessError):
        return None, None
    return commit, dirty


class Provenance:
    """A context manager that samples the load average while a run lasts; ``record()`` after it."""

    def __init__(self, command: str, interval: float = 10.0):
        if not command:
            raise ValueError("Provenance needs the command that reruns the record")
        self.command, self.interval = command, interval
        self.loads: list[float] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self.started = self.seconds = None

    def _sample(self) -> None:
        while True:
            self.loads.append(os.getloadavg()[0])
            if self._stop.wait(self.interval):
                return

    def __enter__(self) -> "Provenance":
        self.started, self._t0 = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), time.perf_counter()
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.seconds = time.perf_counter() - self._t0
        self._stop.set()
        self._thread.join()
        self.loads.append(os.getloadavg()[0])

    def record(self, checkpoint: Optional[Union[str, Path]] = None, seed: Optional[int] = None,
               episodes: Optional[int] = None, **extra) -> dict:
        """The provenance entry of a record (call after the ``with`` block)."""
        if self.seconds is None:
            raise RuntimeError("Provenance.record: call it after the run's `with` block has ended")
        commit, dirty = git_state()
        out = {"command": self.command, "git_commit": commit, "library_modified_since_commit": dirty,
               "python": platform.python_version(), "torch": torch.__version__,
               "torch_threads": torch.get_num_threads(), "cpus": os.cpu_count(),
               "started": self.started, "wall_seconds": round(self.seconds, 1),
               "load_average_mean": round(sum(self.loads) / len(self.loads), 2),
               "load_average_max": round(max(self.loads), 2)}
        if checkpoint is not None:
            out["checkpoint"] = repo_relative(checkpoint)
            out["checkpoint_sha256"] = sha256(checkpoint)
        if seed is not None:
            out["episodes_seed"] = seed
        if episodes is not None:
            out["episodes"] = episodes
        return {**out, **extra}
