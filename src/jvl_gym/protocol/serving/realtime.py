"""What a process that keeps real time does about Python's cyclic garbage collector.

A full collection (generation 2) walks every object the collector tracks, holding the
interpreter lock throughout. A process with the simulator, numba and a policy's torch and
stable-baselines3 loaded tracks some 400 000 objects: one full pass takes about 100 ms on an
idle core of the 2-core machine and 450 ms on a busy one, many control periods of a deployed
policy (11.5 ms over MacTalk) and many samples of a twin served in real time. Such passes come
at moments nobody chose, whenever enough new long-lived objects have piled up.

:func:`heap_frozen` collects once, then freezes the heap (:func:`gc.freeze`): the objects alive
at that moment move to a permanent generation that collections skip, so a full pass walks only
what was made since; objects made inside the block are collected as usual. On leaving the
outermost block the frozen objects go back to the oldest generation (:func:`gc.unfreeze`), so
nothing stays uncollectable after the real-time work ends.
"""

from __future__ import annotations

import contextlib
import gc
import threading
from collections.abc import Iterator

__all__ = ["heap_frozen"]

_lock = threading.Lock()
_depth = 0


@contextlib.contextmanager
def heap_frozen() -> Iterator[None]:
    """Keep full collections short for the block (module docstring); blocks may nest, from any
    thread: the heap is unfrozen when the last one ends. ``@heap_frozen()`` runs a function
    so."""
    global _depth
    with _lock:
        if _depth == 0:
            gc.collect()
            gc.freeze()
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                gc.unfreeze()
