"""A process keeping real time freezes its heap (``protocol.serving.realtime.heap_frozen``):
full collections skip what was alive before, what is made inside is still collected, blocks
nest, and the heap is as it was afterwards. jvl-gym deploy runs its loop that way
(tests/test_deploy.py holds the loop against a twin)."""

from __future__ import annotations

import gc
import threading
import weakref

from jvl_gym.protocol.serving.realtime import heap_frozen


class Node:
    def __init__(self) -> None:
        self.other: Node | None = None


def _cycle() -> weakref.ref[Node]:
    a, b = Node(), Node()
    a.other, b.other = b, a
    return weakref.ref(a)


def test_the_heap_alive_before_is_frozen_and_thawed_after() -> None:
    assert gc.get_freeze_count() == 0
    alive = [[k] for k in range(10_000)]  # tracked containers alive before the block
    with heap_frozen():
        assert gc.get_freeze_count() >= len(alive)
    assert gc.get_freeze_count() == 0


def test_garbage_made_inside_the_block_is_still_collected() -> None:
    with heap_frozen():
        ref = _cycle()
        assert ref() is not None
        gc.collect()
        assert ref() is None


def test_garbage_made_before_the_block_is_collected_first() -> None:
    ref = _cycle()
    with heap_frozen():
        assert ref() is None  # collected before freezing, not kept frozen


def test_nested_blocks_from_two_threads_thaw_only_at_the_last() -> None:
    inner_done, outer_may_end = threading.Event(), threading.Event()
    counts: list[int] = []

    def inner() -> None:
        with heap_frozen():
            counts.append(gc.get_freeze_count())
        counts.append(gc.get_freeze_count())
        inner_done.set()

    with heap_frozen():
        th = threading.Thread(target=inner)
        th.start()
        inner_done.wait(30)
        th.join(30)
        counts.append(gc.get_freeze_count())
        outer_may_end.set()
    assert all(c > 0 for c in counts)  # the inner block's end left the outer one's heap frozen
    assert gc.get_freeze_count() == 0


def test_the_heap_is_thawed_when_the_block_raises() -> None:
    try:
        with heap_frozen():
            raise KeyError("x")
    except KeyError:
        pass
    assert gc.get_freeze_count() == 0
