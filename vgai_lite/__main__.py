"""``python -m vgai_lite COMMAND``: the book's commands (``vgai_lite.lab.cli``)."""

import sys

from .lab.cli import main

if __name__ == "__main__":
    sys.exit(main())
