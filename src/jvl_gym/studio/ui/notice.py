"""The compile notice a page shows while numba compiles kernels (:mod:`..compiling`)."""

from __future__ import annotations

from nicegui import ui

from .. import compiling
from .common import Page, tid

__all__ = ["compile_notice"]


def compile_notice(page: Page) -> None:
    """A line that says what numba compiles while it compiles, hidden otherwise."""
    label = ui.label("").classes("text-warning text-sm").props(tid("compile-notice"))
    label.set_visibility(False)

    def show() -> None:
        text = compiling.current()
        label.set_visibility(text is not None)
        label.set_text(text or "")
    show()
    page.every(1.0, show)
