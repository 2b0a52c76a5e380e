"""The direct entry of a compiled function for arguments whose types never change.

A compiled dispatcher looks up, at every call, the machine code for the types of its arguments
(about 40 ns per argument, some 0.4 µs for the engine's drivers). A caller whose arguments keep
their types for its whole life — a motor array's own arrays, an env's buffers — looks it up
once and calls the machine code's own entry, which converts the arguments by the types found
then and skips the look-up. The caller guarantees the types: the entry converts an argument of
another type by the types it was found for (it checks that an array is an array, not its dtype,
dimensions or layout).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["entry_point"]


def entry_point(dispatcher: Any, args: Sequence[Any]) -> Callable[..., Any]:
    """The entry of the machine code ``dispatcher`` has compiled (or loaded from its cache) for
    the types of ``args``; the dispatcher itself when it has none for them yet (call it once
    with such arguments first) or is not a compiled dispatcher.

    Parameters
    ----------
    dispatcher : compiled dispatcher
        The compiled function.
    args : sequence
        Arguments of the types every later call will pass.

    Returns
    -------
    callable
        Called with arguments of those types, it runs the same machine code as the dispatcher.
    """
    try:
        signature = tuple(dispatcher.typeof_pyval(a) for a in args)
        overload = dispatcher.overloads.get(signature)
    except AttributeError:  # not a compiled dispatcher (e.g. compiling disabled)
        return dispatcher
    return dispatcher if overload is None else overload.entry_point
