"""The book's switches and places: quick mode, the data folder, seeds.

Introduced in notebook 00. Quick mode is read here and nowhere else: set the environment variable
``VGAI_LITE_QUICK=1`` (the test suite does) and every notebook shrinks its loops, via ``pick``:

    episodes = pick(full=50, quick=4)
"""

from __future__ import annotations

import os
from pathlib import Path

QUICK_ENV = "VGAI_LITE_QUICK"


def _read_quick() -> bool:
    raw = os.environ.get(QUICK_ENV, "").strip().lower()
    if raw in ("", "0", "false", "no", "off"):
        return False
    if raw in ("1", "true", "yes", "on"):
        return True
    raise ValueError(f"{QUICK_ENV} must be 1/true/yes/on or 0/false/no/off (or unset), got {raw!r}")


QUICK: bool = _read_quick()
"""True when the book runs in quick mode (under test): smaller N, fewer steps and episodes."""


def pick(full, quick):
    """``quick`` in quick mode, ``full`` otherwise: ``range(pick(2000, 2))``."""
    return quick if QUICK else full


ROOT = Path(__file__).resolve().parent.parent
DATA_DIR = ROOT / "data"
"""Shipped results and checkpoints (``data/`` beside the package)."""

EVAL_SEED = 2020
"""Seed of the held-out initial conditions every evaluation in the book uses; training never
draws from it (training seeds start at 0 and stay below 1000)."""

SELECTION_SEED = 3000
"""Seed of the validation episodes on which the book picks one of several trainings of a
configuration (``runs.choose_seed``): neither the evaluation seed nor any training or per-round
validation seed (seed + 1000)."""
