"""A Zenoh router in a Python process (no ``zenohd`` needed): the meeting point when the server and
its bots run on different machines. ``rocketdrl-ma router server/router.yaml``."""
from __future__ import annotations

import signal
import threading

from .settings import ZenohSettings


def run_router(settings: ZenohSettings, ready=None, stop: threading.Event | None = None) -> None:
    """Open a router session and hold it until SIGINT/SIGTERM (or ``stop`` is set)."""
    if settings.mode != "router":
        raise ValueError(f"zenoh.mode: a router config needs mode 'router', got {settings.mode!r}")
    stop = stop or threading.Event()
    session = settings.open()
    try:
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                signal.signal(sig, lambda *_: stop.set())
        if ready is not None:
            ready(session)
        stop.wait()
    finally:
        session.close()
