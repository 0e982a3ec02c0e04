"""Test-suite set-up (repository root, so it applies to tests/ and notebooks/ alike): quick mode.

The variable is set before any notebook kernel starts, so nbval's kernels inherit it.
"""

import os

os.environ.setdefault("VGAI_LITE_QUICK", "1")
os.environ.setdefault("MPLBACKEND", "Agg")
