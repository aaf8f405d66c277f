"""Remote entrants: a bot process waits for the league's invitations and plays them on the match server.

The bot declares a queryable on ``rocketdrl/<server>/u/<entrant>/invite`` (its own key prefix: with Zenoh
access control only the entrant's user may answer there, and only admins may ask); the league creates the
match with the entrant's slots reserved for the entrant's user (seats: no secret travels in the
invitation), sends it a ``get`` with ``{"match": id, "slots": [...], "signed": <the server's signed create
reply>}``, and the bot answers and joins those slots through the Bot SDK as that user. The bot plays only an
invitation whose reply the server signed (with the key the bot trusts) for a match an admin created with
those slots as the entrant's seats: a forged or foreign invitation is refused and never counted. The league
retries while nobody answers (the bot may still be starting); no answer within the server link's
``join_timeout_s`` means the entrant is not there, and the league stops (the match is stopped on the server and nothing is recorded for it).
"""
from __future__ import annotations

import logging
import queue
import threading
import time
from typing import Callable

from rocketdrl_ma.server.protocol import Keys, pack, unpack

log = logging.getLogger(__name__)
INVITE_TIMEOUT_S = 10.0
MAX_INVITATION_BYTES = 4 * 1024 * 1024  # a create reply carries the match's config
RETRY_S = 0.2  # between invitations while the entrant's bot is not there yet


def invite_key(server: str, entrant: str) -> str:
    return Keys(server).invite(entrant)


def invite(session, server: str, entrant: str, match_id: str, slots: list[str], signed: bytes,
           wait_s: float = INVITE_TIMEOUT_S) -> None:
    """Ask ``entrant``'s bot to join ``slots`` of ``match_id`` (``signed``: the server's signed create reply),
    retrying for ``wait_s`` while no bot answers (it may still be starting); RuntimeError if it refuses or never
    answers."""
    key = invite_key(server, entrant)
    deadline = time.monotonic() + wait_s
    payload = pack({"match": match_id, "slots": slots, "signed": signed})
    while True:
        for reply in session.get(key, payload=payload, timeout=wait_s):
            if reply.ok is not None and unpack(reply.ok.payload.to_bytes()).get("ok"):
                return
            raise RuntimeError(f"remote entrant {entrant!r}: invitation refused on {key}: "
                               f"{reply.err.payload.to_bytes()[:200]!r}")
        if time.monotonic() > deadline:
            raise RuntimeError(f"remote entrant {entrant!r}: no bot answered on {key} within {wait_s} s; start one "
                               f"with `rocketdrl-ma league-bot --entrant {entrant} --policy SPEC --server {server}`")
        time.sleep(RETRY_S)


def check_invitation(server_key, server: str, entrant: str, match_id: str, slots: list, signed) -> None:
    """ValueError unless ``signed`` is the server's signed reply creating ``match_id``, made by an admin, with
    every slot of ``slots`` the entrant's seat."""
    from rocketdrl_ma.server.crypto import SignatureError
    from rocketdrl_ma.server.protocol import ProtocolError, open_sealed
    if not isinstance(signed, bytes):
        raise ValueError("invitation: not signed by the server (no signed create reply)")
    try:
        body = open_sealed(server_key, signed, MAX_INVITATION_BYTES)
    except (ProtocolError, SignatureError) as e:
        raise ValueError(f"invitation: not signed by the server ({e})") from None
    seats = (body.get("options") or {}).get("seats") or {}
    if body.get("kind") != "reply" or body.get("op") != "create" or body.get("ok") is not True \
            or body.get("server") != server or body.get("id") != match_id:
        raise ValueError(f"invitation: the signed reply does not create match {match_id!r} on server {server!r}")
    if body.get("creator_role") != "admin":
        raise ValueError(f"invitation: match {match_id!r} was created by {body.get('creator')!r}, not an admin")
    foreign = [s for s in slots if seats.get(s) != entrant]
    if foreign:
        raise ValueError(f"invitation: slot(s) {foreign} of match {match_id!r} are not {entrant!r}'s seats")


def serve_invitations(session, server: str, entrant: str, make_bot: Callable[[], object],
                      max_matches: int | None = None, stop: threading.Event | None = None,
                      on_match: Callable[[str, list], None] | None = None, client=None) -> int:
    """Play every match the league invites ``entrant`` to (``make_bot()`` -> a fresh ``Bot`` per car) until
    ``max_matches`` were played or ``stop`` is set; the number of matches played. ``client``: a
    ``ClientSettings`` for the server (its user must be ``entrant``; default: unauthenticated, as it)."""
    from rocketdrl_ma.server.client import LobbyClient, resolve_client

    client = resolve_client(client, server=server, user=entrant)
    server_key = LobbyClient(session, client).server_key  # trusted before any invitation is read
    invitations: queue.Queue = queue.Queue()
    stop = stop or threading.Event()

    def on_query(query) -> None:
        try:
            request = unpack(query.payload.to_bytes())
            match_id, slots = request.get("match"), request.get("slots")
            if not isinstance(match_id, str) or not isinstance(slots, list) or not slots:
                raise ValueError("invitation: expected a match id and a list of slots")
            check_invitation(server_key, server, entrant, match_id, slots, request.get("signed"))
        except Exception as e:
            query.reply_err(pack({"ok": False, "error": str(e)}))
            return
        invitations.put((match_id, slots))
        query.reply(query.key_expr, pack({"ok": True}))

    queryable = session.declare_queryable(invite_key(server, entrant), on_query)
    played = 0
    try:
        while not stop.is_set() and (max_matches is None or played < max_matches):
            try:
                match_id, slots = invitations.get(timeout=0.5)
            except queue.Empty:
                continue
            reports: list = []
            # Not daemon threads: Zenoh runs the callbacks a thread declares on a Python thread of the same
            # daemon-ness, and a daemon one may wake in interpreter shutdown and abort the process.
            threads = [threading.Thread(target=lambda s=slot: reports.append(
                make_bot().run(match_id, s, client=client, session=session))) for slot in slots]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            played += 1
            log.info("played %s as %s", match_id, slots)
            if on_match is not None:
                on_match(match_id, reports)
    finally:
        queryable.undeclare()
    return played
