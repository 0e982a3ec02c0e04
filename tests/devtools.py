"""The browser tests' DevTools helpers: the library's own (``vgai_lite.lab.chromium``), which the
PDF of the book (``vgai_lite.lab.pdf``) prints with."""

from vgai_lite.lab.chromium import CHROMIUM, DevTools, free_port, start_chromium, stop, wait_http  # noqa: F401
