"""The book's switches and places: quick mode, the data folder, the seeds of its episode sets.

Introduced in notebook 00. Quick mode is read here and nowhere else: set the environment variable
``VGAI_LITE_QUICK=1`` (the test suite does) and every notebook shrinks its loops, via ``pick``:

    episodes = pick(full=50, quick=4)
"""

from __future__ import annotations

import importlib.resources
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


THREADS_ENV = "VGAI_LITE_THREADS"


def threads() -> int:
    """The torch threads a notebook uses: ``VGAI_LITE_THREADS`` if set (the test suite sets 1 when
    it runs two notebooks at a time on two cores, so that they do not oversubscribe them), else 2,
    the cores of the machines the book is written for."""
    raw = os.environ.get(THREADS_ENV, "").strip()
    if not raw:
        return 2
    if not raw.isdigit() or int(raw) < 1:
        raise ValueError(f"{THREADS_ENV} must be a positive whole number of threads, got {raw!r}")
    return int(raw)


QUICK_T = 30
"""Steps per episode of every quick run of the command line (``reproduce --quick``, the quick robustness
sweep): the notebooks' quick mode and the quick runs the tests make, a few seconds each."""
QUICK_TRAIN_N = 12
"""Agents of the trainings of a quick run (rendering is a VGAI training's cost; the cells still fly
their columns' N)."""


def pick(full, quick):
    """``quick`` in quick mode, ``full`` otherwise: ``range(pick(2000, 2))``."""
    return quick if QUICK else full


ROOT = Path(__file__).resolve().parent.parent
DATA_DIR = ROOT / "data"
"""The repository's results and checkpoints (``data/`` beside the package), where the book reads and
writes its records."""


def shipped_file(relative: str) -> Path:
    """A file the book ships, e.g. ``"vgai/vgai_F24.pt"``: from ``DATA_DIR`` when the library runs from
    its repository, else from the installed package's data (``vgai_lite/shipped/``, the wheel's copy
    of ``data/vgai`` and ``data/dagnn``, read through ``importlib.resources``)."""
    local = DATA_DIR / relative
    if local.is_file():
        return local
    installed = importlib.resources.files("vgai_lite") / "shipped" / relative
    if installed.is_file():
        return Path(str(installed))
    raise FileNotFoundError(f"no shipped file {relative!r} in {DATA_DIR} or in the installed package "
                            f"(vgai_lite/shipped/): the book ships data/vgai/*.pt and data/dagnn/*.pt")

VALIDATION_SEED = 3000
"""Seed of the validation episodes: every design and recipe choice, and the pick of one of several
trainings of a configuration (``runs.choose_seed``), is made on these episodes and on no others."""

TEST_SEED = 5000
"""Seed of the test episodes: only the numbers the book reports for the controllers it ships are
flown on them; nothing is chosen on them (notebook 01's table of episode sets says why)."""

WORKING_SEED = 2020
"""Seed of the working episodes: the chapters' pictures and worked experiments. Held out from every
training (training seeds start at 0 and their round checks at 1000), but the chapters compare designs
on them while they teach, so they are neither validation nor test episodes."""


def prose(template: str, **values):
    """Markdown whose numbers are computed, for a notebook's output: every measured number in the
    book's prose is rendered this way, so it cannot go stale (tests/test_notebook_sources.py checks
    that the markdown cells hold no other measured numbers).

        prose("Local costs {ratio:.1f}× the expert's.", ratio=local_cost / expert_cost)

    ``template`` is a ``str.format`` template; each ``{name}`` must be given, and only finite numbers
    (or strings) may fill it: a NaN in prose is a bug to see, not to print."""
    import math
    import string

    from IPython.display import Markdown

    wanted = {f for _, f, _, _ in string.Formatter().parse(template) if f}
    names = {f.split(".")[0].split("[")[0] for f in wanted}
    missing, extra = sorted(names - set(values)), sorted(set(values) - names)
    if missing or extra:
        raise ValueError(f"prose: the template needs {sorted(names)}; missing {missing}, unused {extra}")
    for k, x in values.items():
        if isinstance(x, float) and not math.isfinite(x):
            raise ValueError(f"prose: {k} = {x!r} is not a finite number")
    return Markdown(template.format(**values))
