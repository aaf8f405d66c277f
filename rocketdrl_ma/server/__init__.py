"""The Zenoh face: a match server that remote bots join, the Bot SDK, spectating.

``rocketdrl_ma.server.Bot`` (subclass it, implement ``act``, call ``run``), ``PolicyBot``,
``Spectator`` (verified, typed states and events of a match), ``LobbyClient``, ``ClientSettings`` and
``MatchServer`` are imported on first use, so ``rocketdrl_ma.commands.server`` (the CLI) loads nothing
heavy.
"""
from __future__ import annotations

import importlib

_EXPORTS = {"Bot": "bot", "PolicyBot": "bot", "BotReport": "bot", "LobbyClient": "client", "JoinInfo": "client",
            "ServerError": "client", "ServerGone": "client", "MatchServer": "lobby", "ServerSettings": "settings",
            "MatchOptions": "settings", "ZenohSettings": "settings", "ClientSettings": "settings",
            "Spectator": "spectator", "StateUpdate": "spectator", "EventsUpdate": "spectator",
            "MatchEnd": "spectator", "PROTOCOL_VERSION": "protocol"}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
