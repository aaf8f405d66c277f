"""The match server: one Zenoh session, the lobby queryable, bot liveliness, several matches at once.

Lobby requests are msgpack maps ``{"v": 1, "op": ..., ...}`` sent with a Zenoh ``get`` on
``rocketdrl/<server>/lobby``; the reply is ``{"v": 1, "ok": true, ...}`` or an error reply
``{"v": 1, "ok": false, "error": "..."}`` (ops: create, list, inspect, stop, join, leave).
"""
from __future__ import annotations

import logging
import secrets
import threading
from typing import Any

from rocketdrl_ma.results import MatchResult, ResultsStore

from .match import ENDED, MatchRunner
from .protocol import MAX_REQUEST_BYTES, Keys, ProtocolError, check_name, pack, unpack
from .settings import MatchOptions, ServerSettings
from .slots import same_token

log = logging.getLogger(__name__)
ADMIN_OPS = ("create", "stop")


class MatchServer:
    """``MatchServer(settings).start()`` serves until ``close()``; matches run in their own threads."""

    def __init__(self, settings: ServerSettings, results_path: str | None = None):
        self.settings = settings
        self.keys = Keys(settings.name)
        self.store = ResultsStore(results_path or settings.results)
        self.matches: dict[str, MatchRunner] = {}
        self._lock = threading.Lock()
        self._store_lock = threading.Lock()
        self.session = None
        self._declared: list[Any] = []
        self.requests_rejected = 0

    # ------------------------------------------------------------------------------------------ lifecycle
    def start(self) -> "MatchServer":
        self.session = self.settings.zenoh.open()
        try:
            s = self.session
            self._declared = [
                s.declare_queryable(self.keys.lobby, self._on_query),
                s.liveliness().declare_subscriber(self.keys.all_bot_alive, self._on_liveliness, history=True),
                s.liveliness().declare_token(self.keys.server_alive),
            ]
            for entry in self.settings.matches:
                entry = dict(entry)
                match_id = entry.pop("id", None)
                self.create(MatchOptions.from_dict(entry, self.settings.match_defaults), match_id)
        except Exception:
            self.close()
            raise
        return self

    def close(self) -> None:
        with self._lock:
            matches = list(self.matches.values())
        for match in matches:
            match.stop()
        for match in matches:
            match.join_thread(10.0)
        for declared in reversed(self._declared):
            try:
                declared.undeclare()
            except Exception:
                pass
        self._declared = []
        if self.session is not None:
            self.session.close()
            self.session = None
        self.store.close()

    def __enter__(self) -> "MatchServer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------------------------------ matches
    def _record(self, result: MatchResult) -> None:
        with self._store_lock:
            self.store.append(result)

    def create(self, options: MatchOptions, match_id: str | None = None) -> MatchRunner:
        match_id = check_name("id", match_id) if match_id is not None else secrets.token_hex(4)
        with self._lock:
            if match_id in self.matches:
                raise ValueError(f"id: a match {match_id!r} already exists on server {self.settings.name!r}")
            self._forget_old()
            runner = MatchRunner(match_id, options, self.session, self.keys, self._record)
            self.matches[match_id] = runner
        runner.start()
        log.info("match %s created (%s, %s)", match_id, options.config, options.mode)
        return runner

    def _forget_old(self) -> None:
        """Keep at most ``max_finished_kept`` ended matches in memory (their results are in the store)."""
        ended = [m for m in self.matches.values() if m.status in ENDED]
        for match in ended[:max(0, len(ended) - self.settings.max_finished_kept + 1)]:
            del self.matches[match.id]

    def match(self, match_id: Any) -> MatchRunner:
        with self._lock:
            runner = self.matches.get(match_id) if isinstance(match_id, str) else None
        if runner is None:
            raise ValueError(f"match: no match {match_id!r} on server {self.settings.name!r}")
        return runner

    # ------------------------------------------------------------------------------------------ Zenoh side
    def _on_liveliness(self, sample) -> None:
        import zenoh
        parsed = self.keys.parse_bot_alive(str(sample.key_expr))
        if parsed is None:
            return
        match_id, slot, lease = parsed
        with self._lock:
            runner = self.matches.get(match_id)
        if runner is not None:
            runner.set_alive(slot, lease, sample.kind == zenoh.SampleKind.PUT)

    def _on_query(self, query) -> None:
        try:
            payload = query.payload
            if payload is None:
                raise ProtocolError("message: the lobby needs a msgpack request as the query payload")
            reply = self.handle(unpack(payload.to_bytes(), MAX_REQUEST_BYTES))
            query.reply(self.keys.lobby, pack(reply))
        except ValueError as e:  # ProtocolError included: every bad request gets a reason back
            self.requests_rejected += 1
            query.reply_err(pack({"ok": False, "error": str(e)}))
        except Exception as e:
            log.exception("lobby request failed")
            query.reply_err(pack({"ok": False, "error": f"internal error: {type(e).__name__}: {e}"}))

    def handle(self, request: dict) -> dict:
        """Answer one lobby request (already decoded and version-checked)."""
        op = request.get("op")
        if op in ADMIN_OPS and self.settings.admin_token is not None \
                and not same_token(request.get("admin_token"), self.settings.admin_token):
            raise ValueError(f"admin_token: op {op!r} needs this server's admin token")
        if op == "create":
            fields = {k: v for k, v in request.items() if k not in ("v", "op", "id", "admin_token")}
            runner = self.create(MatchOptions.from_dict(fields, self.settings.match_defaults), request.get("id"))
            return {"ok": True, **runner.inspect()}
        if op == "list":
            with self._lock:
                runners = list(self.matches.values())
            return {"ok": True, "server": self.settings.name, "matches": [m.summary() for m in runners]}
        if op == "inspect":
            return {"ok": True, **self.match(request.get("match")).inspect()}
        if op == "stop":
            runner = self.match(request.get("match"))
            runner.stop()
            return {"ok": True, "match": runner.id}
        if op == "join":
            return self.match(request.get("match")).join(request)
        if op == "leave":
            return self.match(request.get("match")).leave(request)
        raise ValueError(f"op: unknown lobby op {op!r}; allowed: ['create', 'list', 'inspect', 'stop', 'join', "
                         "'leave']")
