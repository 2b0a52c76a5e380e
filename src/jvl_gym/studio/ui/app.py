"""Build the studio's pages on a :class:`~jvl_gym.studio.session.Session` and serve them.

NiceGUI serves the pages (FastAPI and uvicorn underneath, Vue and Quasar in the browser, ECharts
for the live charts); each page updates itself over its websocket from timers on the server.
The whole application, pages, uploads and the websocket alike, sits behind the studio's lock
(:class:`~jvl_gym.studio.lock.StudioLock`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from ..lock import Access, StudioLock
from ..session import Session

__all__ = ["serve", "RECONNECT_S"]

#: seconds a page waits for its websocket to come back before it reloads (a busy machine
#: may hold the server up for seconds)
RECONNECT_S = 30.0


def build(session: Session) -> None:
    """Register the studio's pages for ``session``: a view that needs a motor sends a studio
    without one to the Connections view."""
    from fastapi.responses import RedirectResponse
    from nicegui import app, ui

    from ..connections import Connections
    from . import (
        connections_page,
        episodes_page,
        motors_page,
        registers_page,
        scope_page,
        tuning_page,
    )
    from .common import WITHOUT_MOTOR

    connections = Connections(session)

    def route(path: str, builder: Callable[[Session, int], None]
              ) -> Callable[[int], RedirectResponse | None]:
        def page(m: int = 0) -> RedirectResponse | None:
            if not session.motors and path not in WITHOUT_MOTOR:
                return RedirectResponse("/connections")
            builder(session, m)
            return None
        return page

    for path, module in (("/", motors_page), ("/registers", registers_page),
                         ("/scope", scope_page), ("/tuning", tuning_page),
                         ("/episodes", episodes_page)):
        ui.page(path)(route(path, module.build))
    ui.page("/connections")(route("/connections",
                                  lambda s, m: connections_page.build(connections, m)))
    app.on_startup(session.start)
    app.on_shutdown(session.stop)


def serve(session: Session, access: Access, host: str = "127.0.0.1",
          show: bool = True) -> None:
    """Serve the studio of ``session`` on ``host``:``access.port`` behind the lock of
    ``access`` until Ctrl-C (``show``: open the browser at the URL with the token)."""
    import matplotlib

    matplotlib.use("Agg")
    from nicegui import app, ui

    logging.getLogger("jvl_gym.studio").setLevel(logging.INFO)
    build(session)
    app.add_middleware(StudioLock, access=access)
    ui.run(host=host, port=access.port,
           show=access.path("/") if show else False,
           reload=False, title="jvl-gym studio", show_welcome_message=False, favicon="⚙",
           uvicorn_logging_level="warning", reconnect_timeout=RECONNECT_S)
