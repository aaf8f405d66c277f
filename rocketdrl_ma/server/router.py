"""A Zenoh router in a Python process (no ``zenohd`` needed): the meeting point when the server and
its bots run on different machines. ``rocketdrl-ma router server/router.yaml``.

A router YAML has a ``zenoh:`` section (mode router) and ``serves:``, the server YAML whose ``access``
users it authenticates and whose access-control rules it enforces (the server connects to it as the
user ``server``; bots and spectators as their own users, in client mode).
"""
from __future__ import annotations

import signal
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

from rocketdrl_ma.config import load_yaml_mapping
from rocketdrl_ma.validation import Check, load_dataclass

from .access import acl_config, read_users_file
from .settings import SERVER_USER, ServerSettings, ZenohSettings


def _served(field: str, serves: Any) -> ServerSettings | None:
    if serves is not None and not isinstance(serves, (str, ServerSettings)):
        raise ValueError(f"{field}: expected the path of the server YAML, got {serves!r}")
    return ServerSettings.load(serves) if isinstance(serves, str) else serves


@dataclass(frozen=True)
class RouterSettings:
    zenoh: ZenohSettings
    serves: Annotated[Any, Check(_served)] = None
    """the server YAML whose users and access rules the router enforces (its path, or the settings); null: none"""

    @classmethod
    def from_dict(cls, d: dict) -> "RouterSettings":
        return load_dataclass(cls, d, "router")

    def check(self) -> None:
        zenoh = self.zenoh
        if zenoh.mode != "router":
            raise ValueError(f"zenoh.mode: a router config needs mode 'router', got {zenoh.mode!r}")
        if zenoh.remote_listen() and not zenoh.insecure and (self.serves is None or not self.serves.access.enabled):
            raise ValueError(f"serves: the router listens beyond loopback ({zenoh.remote_listen()}) but "
                             "authenticates nobody; name the server YAML whose access.users it enforces, or set "
                             "zenoh.insecure: true on a network you trust")

    @classmethod
    def load(cls, path: str | Path) -> "RouterSettings":
        return cls.from_dict(load_yaml_mapping(path, "router config"))

    @property
    def server_name(self) -> str | None:
        return self.serves.name if self.serves is not None else None

    def zenoh_extra(self) -> dict[str, Any]:
        if self.serves is None or not self.serves.access.enabled:
            return {}
        access = self.serves.access
        users = read_users_file(self.serves.users_path)
        missing = sorted({SERVER_USER, *access.roles} - set(users))
        if missing:
            raise ValueError(f"access.users_file: users {missing} have no password")
        return {"transport/auth/usrpwd/dictionary_file": str(self.serves.users_path),
                "access_control": acl_config(self.serves.name, access.roles, router=True)}


def run_router(settings: RouterSettings | ZenohSettings, ready=None, stop: threading.Event | None = None) -> None:
    """Open a router session and hold it until SIGINT/SIGTERM (or ``stop`` is set)."""
    if isinstance(settings, ZenohSettings):
        settings = RouterSettings.from_dict({"zenoh": settings})
    stop = stop or threading.Event()
    session = settings.zenoh.open(settings.zenoh_extra())
    try:
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                signal.signal(sig, lambda *_: stop.set())
        if ready is not None:
            ready(session)
        stop.wait()
    finally:
        session.close()
