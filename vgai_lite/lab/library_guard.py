"""While an exercise's check runs the student's answer, the library's own implementation of what the
exercise asks for raises, however the answer reaches it: under an alias, as ``vl.name`` or
``module.name``, from a subclass. The very function objects are changed for the duration of the
call (their ``__code__``), not the names, so no path around it is left; every other library function
works as usual, and the check's own reference computations, run outside the answer, too.
"""

from __future__ import annotations

from typing import Callable

LIBRARY_CALL = "vgai-lite library call: "
"""The message of the error a library function raises while it is forbidden (``without_library``)."""


def _forbidden_code(func: Callable):
    """A code object that raises, naming ``func``, whatever it is called with (no free variables, builtins
    only, so that it can stand in ``func.__code__`` inside ``func``'s own module)."""
    qualified = f"{func.__module__}.{func.__qualname__}"
    free = func.__code__.co_freevars  # e.g. __class__ of a method that calls super(): as many, as the slot needs
    source = ("def outer():\n" + "".join(f"    {v} = None\n" for v in free)
              + f"    def {func.__name__}(*args, **kwargs):\n"
              + (f"        {', '.join(free)}\n" if free else "")
              + f"        raise PermissionError({LIBRARY_CALL + qualified!r})\n"
              + f"    return {func.__name__}\n")
    namespace: dict = {}
    exec(source, namespace)
    return namespace["outer"]().__code__


class without_library:
    """While active, the library's own implementations ``funcs`` raise when called, however they are
    reached (under an alias, as ``vl.name`` or ``module.name``, from a subclass): the very function
    objects are changed, not the names. The checks run the student's answer inside it, so that an
    answer that calls what the exercise asks to write is told so; every other library function works."""

    def __init__(self, *funcs: Callable):
        self.funcs = funcs

    def __enter__(self):
        self.saved = [(f, f.__code__) for f in self.funcs]
        for f in self.funcs:
            f.__code__ = _forbidden_code(f)
        return self

    def __exit__(self, *exc):
        for f, code in self.saved:
            f.__code__ = code


def guarded(student_fn: Callable, *library: Callable) -> Callable:
    """``student_fn`` run ``without_library(*library)`` at every call."""
    def call(*args, **kwargs):
        with without_library(*library):
            return student_fn(*args, **kwargs)
    return call
