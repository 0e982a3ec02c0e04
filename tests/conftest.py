"""Test-suite set-up: the book runs in quick mode under test (notebooks included).

The variable is set before any notebook kernel starts, so nbval's kernels inherit it.
"""

import os

os.environ.setdefault("VGAI_LITE_QUICK", "1")
os.environ.setdefault("MPLBACKEND", "Agg")
