"""The page server: one port for the page's files (HTTP GET) and the page's websocket (``/ws``).

The websocket speaks JSON requests in and msgpack messages out (``frames.py``). Requests:

    {"op": "list"}                                  -> {"type": "list", "matches", "training", "replays", "zenoh"}
    {"op": "watch", "kind": "match"|"train", "id"}  -> roster, then frames (at most ``max_rate`` a second),
                                                       status changes, and the final message
    {"op": "replay", "id"}                          -> {"type": "replay", "roster", "frames", ...}
    {"op": "league_replay", "key"}                  -> a league's stored match played again from its seed, as a
                                                       replay (``rocketdrl-ma web --league LEAGUE.yaml``)
    {"op": "stop"}                                  -> stops following

With ``play`` (``rocketdrl-ma web --play``, loopback only) a page may also take a seat (``play.py``):

    {"op": "play", "match": id[, "slot"]}          -> {"type": "seat", ...}, then follows the match
    {"op": "play", "config", "opponent"}            -> creates a real-time match against bots, then as above
    {"op": "input", "c": [8 controls], "n": seq}    -> drives this page's own seat; {"type": "ack", "n"}
    {"op": "leave"}                                 -> gives the seat up (so does closing the page)

Without it the page server is read-only by construction: it never joins a match, never sends an action and
publishes nothing on Zenoh; no request can reach a car. Requests for anything else get an error message.
With a league (``--league``), ``/league`` is its page: standings, ratings, payoff matrix and matches, from
``/api/league``. The page's own origin is the only one allowed to open the websocket, and the Host header must name the
address the server listens on (no DNS rebinding onto a loopback page server).
"""
from __future__ import annotations

import asyncio
import ipaddress
import json
import logging
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from rocketdrl_ma.config import REPO_ROOT
from rocketdrl_ma.physics.compile_notice import COLD_COMPILE_ESTIMATE_S
from rocketdrl_ma.rules.events import GameEvent
from rocketdrl_ma.server.client import LobbyClient, resolve_client
from rocketdrl_ma.server.protocol import ENDED_STATUSES
from rocketdrl_ma.validation import check_name

from .arena import arena_json
from .feed import SOURCE_KINDS, FeedUpdate, Follower, SpectatorFeed
from .frames import feed_events, frame, pack_message, roster
from .play import PLAY_CONFIGS, HumanSeat, create_match
from .replays import ReplayLibrary

if TYPE_CHECKING:  # the league's modules load only for a page server that shows one
    from .league import LeagueView

log = logging.getLogger(__name__)
STATIC_DIR = Path(__file__).parent / "static"
PACKAGED_VENDOR_DIR = Path(__file__).parent / "vendor"  # in a wheel: the page's npm files, node_modules' layout
MAX_STATES_PER_S = 30.0
#: a page that plays gets its match's states up to this rate: the server's tick rate, so a state of a real-time
#: match (60 a second) that came sooner than 1/60 s after the last one is not held back
PLAYER_STATES_PER_S = 120.0
#: with nothing arriving, how often a followed source is looked at anyway (the first-state hint, a silent server)
IDLE_LOOK_S = 0.25
MAX_REQUEST_BYTES = 64 * 1024
#: a followed source with no state after this long gets a hint on the page (kernels compiling, bots joining)
FIRST_STATE_HINT_S = 2.0
WATCH_OPS = ("list", "watch", "replay", "league_replay", "stop")
PLAY_OPS = ("play", "input", "leave")
OPS = WATCH_OPS + PLAY_OPS
#: how long a stopping page server waits for each seat's thread (it ends at its match's next decision)
SEAT_STOP_S = 2.0
CONTENT_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
                 ".mjs": "text/javascript; charset=utf-8", ".css": "text/css; charset=utf-8",
                 ".json": "application/json", ".png": "image/png", ".svg": "image/svg+xml"}


def find_node_modules(extra: list[Path] = ()) -> Path:
    """The ``node_modules`` holding three.js: given, the copy an installed wheel carries (``setup.py``), the
    repository's (``npm ci`` there), or the working directory's."""
    for folder in [*extra, PACKAGED_VENDOR_DIR, REPO_ROOT / "node_modules", Path.cwd() / "node_modules"]:
        if (folder / "three" / "build" / "three.module.js").is_file():
            return folder
    raise ValueError("web: three.js is not installed; run `npm ci` in the repository (or `make web-deps`), or "
                     "pass --node-modules PATH")


def vendor_files(node_modules: Path) -> dict[str, Path]:
    """URL path -> file of every front-end dependency the page imports (nothing else is served from there)."""
    three = node_modules / "three"
    files = {f"/vendor/three/{name}": three / "build" / name for name in ("three.module.js", "three.core.js")}
    msgpack_dir = node_modules / "@msgpack" / "msgpack" / "dist.esm"
    files.update({f"/vendor/msgpack/{p.relative_to(msgpack_dir).as_posix()}": p
                  for p in sorted(msgpack_dir.rglob("*.mjs"))})
    for url, path in files.items():
        if not path.is_file():
            raise ValueError(f"web: {path} is missing; run `npm ci` in the repository")
    return files


def is_loopback_host(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass
class FrameStats:
    """What the bridge sent: frames, their sizes, and the send times of the last ones (the rate)."""
    frames: int = 0
    bytes_total: int = 0
    bytes_max: int = 0
    bytes_max_cars: int = 0
    min_interval_s: float | None = None  # shortest time between two frames sent to one page
    recent: deque = field(default_factory=lambda: deque(maxlen=600))

    def add(self, n_bytes: int, n_cars: int, interval_s: float | None) -> None:
        self.frames += 1
        self.bytes_total += n_bytes
        if n_bytes > self.bytes_max:
            self.bytes_max, self.bytes_max_cars = n_bytes, n_cars
        if interval_s is not None and (self.min_interval_s is None or interval_s < self.min_interval_s):
            self.min_interval_s = interval_s
        self.recent.append(time.monotonic())

    def as_dict(self) -> dict:
        times = list(self.recent)
        span = times[-1] - times[0] if len(times) > 1 else 0.0
        return {"frames": self.frames, "bytes_mean": self.bytes_total / self.frames if self.frames else None,
                "bytes_max": self.bytes_max, "cars_in_largest": self.bytes_max_cars,
                "min_interval_s": self.min_interval_s,
                "states_per_s_recent": (len(times) - 1) / span if span > 0 else None}


def kickoff_countdown_s(game_config: object) -> float | None:
    """The kickoff countdown of a match's config (the page counts it down), None when unknown."""
    value = game_config.get("kickoff_countdown_s") if isinstance(game_config, dict) else None
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def first_state_hint(kind: str, info: dict) -> str:
    """What the page says while a followed source has published no state yet."""
    if kind == "train":
        return "waiting for the run's next evaluation episode"
    compiling = (f"a match server's first match compiles its physics kernels first (once per machine, "
                 f"~{COLD_COMPILE_ESTIMATE_S} s or more on a busy machine; `rocketdrl-ma warmup` does it ahead)")
    if info.get("status") == "waiting":
        return f"waiting for the match to start (its bots joining, or its ready timeout); then {compiling}"
    return f"no state yet: {compiling}"


class PageServer:
    """``await PageServer(...).serve(stop)`` serves until ``stop`` is set. ``feed`` opens lazily (and again
    after a failure), so the page works for replays with no match server up."""

    def __init__(self, make_feed: Callable[[], SpectatorFeed] | None, library: ReplayLibrary, *,
                 host: str = "127.0.0.1", port: int = 8765, max_rate: float = MAX_STATES_PER_S,
                 node_modules: Path | None = None, play_opponents: list[str] | None = None,
                 league: LeagueView | None = None):
        """``play_opponents``: the policies a page may play against (``play.opponent_choices``); None: no play.
        ``league``: the league the ``/league`` page shows (its replays' folder must be one of ``library``'s)."""
        if not 0 < max_rate <= MAX_STATES_PER_S:
            raise ValueError(f"max_rate: states per second in (0, {MAX_STATES_PER_S:g}], got {max_rate!r}")
        if play_opponents is not None and not is_loopback_host(host):
            raise ValueError(f"play: a page that drives cars is served on loopback only, not on {host!r}")
        self.play_opponents = play_opponents
        self._tickets: dict[str, dict[str, str]] = {}  # the slots' tickets of the matches created for pages
        self._seats: set[HumanSeat] = set()  # the pages' seats, left when the page server stops
        self.make_feed, self.library, self.league = make_feed, library, league
        self.host, self.port, self.max_rate = host, port, float(max_rate)
        self.files = {"/": STATIC_DIR / "index.html", "/league": STATIC_DIR / "league.html"}
        self.files.update({f"/app/{p.name}": p for p in sorted(STATIC_DIR.iterdir()) if p.is_file()})
        self.files.update(vendor_files(node_modules or find_node_modules()))
        self.stats = FrameStats()
        self._feed: SpectatorFeed | None = None
        self._feed_error: str | None = None
        self._feed_lock = asyncio.Lock()
        self.bound_port: int | None = None

    # -------------------------------------------------------------------------------------------- HTTP side
    def _host_allowed(self, host_header: str) -> bool:
        """A loopback page server answers only requests addressed to a loopback name (DNS rebinding)."""
        if not is_loopback_host(self.host):
            return True
        name = host_header[1:].split("]", 1)[0] if host_header.startswith("[") else host_header.rsplit(":", 1)[0]
        return is_loopback_host(name)

    def _process_request(self, connection, request):
        from websockets.datastructures import Headers
        from websockets.http11 import Response

        def respond(status: int, reason: str, body: bytes, content_type: str = "text/plain; charset=utf-8"):
            headers = Headers([("Content-Type", content_type), ("Content-Length", str(len(body))),
                               ("Cache-Control", "no-cache"), ("X-Content-Type-Options", "nosniff")])
            return Response(status, reason, headers, body)

        host = request.headers.get("Host", "")
        if not self._host_allowed(host):
            return respond(403, "Forbidden", f"host {host!r} is not this page server\n".encode())
        path = request.path.split("?", 1)[0]
        if path == "/ws":
            origin = request.headers.get("Origin")
            if origin is not None and origin not in (f"http://{host}", f"https://{host}"):
                return respond(403, "Forbidden", b"websocket: only the page's own origin may connect\n")
            return None  # the websocket handshake goes on
        if path == "/arena.json":
            return respond(200, "OK", arena_json(), CONTENT_TYPES[".json"])
        if path == "/api/stats":
            return respond(200, "OK", json.dumps(self.stats.as_dict()).encode(), CONTENT_TYPES[".json"])
        if path == "/api/league":
            if self.league is None:
                return respond(404, "Not Found", b"no league: start the page server with --league LEAGUE.yaml\n")
            return respond(200, "OK", json.dumps(self.league.summary()).encode(), CONTENT_TYPES[".json"])
        file = self.files.get(path)
        if file is None:
            return respond(404, "Not Found", f"{path}: not found\n".encode())
        return respond(200, "OK", file.read_bytes(), CONTENT_TYPES.get(file.suffix, "application/octet-stream"))

    # -------------------------------------------------------------------------------------------- Zenoh side
    async def _get_feed(self) -> SpectatorFeed | None:
        if self.make_feed is None:
            return None
        async with self._feed_lock:
            if self._feed is None:
                try:
                    self._feed = await asyncio.to_thread(lambda: self.make_feed().open())
                    self._feed_error = None
                except ValueError as e:  # no server or router reachable (yet): try again at the next request
                    self._feed_error = str(e)
            return self._feed

    async def _list(self) -> dict:
        feed = await self._get_feed()
        matches, training = [], []
        if feed is not None:
            matches, training = await asyncio.gather(asyncio.to_thread(feed.matches),
                                                     asyncio.to_thread(feed.training_runs))
        replays = await asyncio.to_thread(self.library.list)  # walks folders: off the event loop
        play = None
        if self.play_opponents is not None and feed is not None:
            play = {"configs": list(PLAY_CONFIGS), "opponents": self.play_opponents}
        return {"type": "list", "matches": matches, "training": training, "replays": replays, "play": play,
                "zenoh": {"server": feed.server if feed else None, "error": self._feed_error,
                          "connected": feed is not None}}

    async def _take_seat(self, request: dict) -> HumanSeat:
        """Seat this page in a match (created for it when the request names a config): ValueError if refused."""
        feed = await self._get_feed()
        if feed is None:
            raise ValueError(f"zenoh: no match server reachable ({self._feed_error})")
        client = resolve_client(None, server=feed.server, zenoh=feed.settings)
        if "config" in request:
            lobby = LobbyClient(feed.session, client)
            created = await asyncio.to_thread(create_match, lobby, request.get("config"), request.get("opponent"),
                                              self.play_opponents)
            match, slot = created["id"], request.get("slot")
            self._tickets[match] = dict(created.get("tickets") or {})
        else:
            match, slot = check_name("match", request.get("match")), request.get("slot")
        if slot is not None:
            slot = check_name("slot", slot)
        tickets = self._tickets.get(match, {})
        if slot is None and tickets:
            slot = next(iter(tickets))  # a match created here: its first slot (blue_0)
        seat = HumanSeat("human", feed.session, client)
        self._seats.add(seat)
        try:
            await asyncio.to_thread(seat.start, match, slot, tickets.get(slot) if slot else None)
        except ValueError:
            self._seats.discard(seat)
            raise
        return seat

    # -------------------------------------------------------------------------------------------- websocket
    async def _handler(self, ws) -> None:
        # the source this page follows: the task pumping it, and its follower (closed here too, since a task
        # cancelled before it first ran never reaches its own clean-up)
        follow: tuple[asyncio.Task, Follower] | None = None
        seat: HumanSeat | None = None  # this page's own slot, if it plays

        def stop_following() -> None:
            nonlocal follow
            if follow is not None:
                follow[0].cancel()
                follow[1].close()
                follow = None

        try:
            async for message in ws:
                try:
                    if isinstance(message, bytes):
                        raise ValueError("request: send JSON text, not binary")
                    request = json.loads(message)
                    if not isinstance(request, dict):
                        raise ValueError("request: expected a JSON object")
                    op = request.get("op")
                    if op not in (OPS if self.play_opponents is not None else WATCH_OPS):
                        raise ValueError(f"op: {op!r} is not one of {list(WATCH_OPS)}" + (
                            f" or {list(PLAY_OPS)}" if self.play_opponents is not None else
                            " (the page is read-only; `rocketdrl-ma web --play` lets it play)"))
                    if op == "input":
                        if seat is None:
                            raise ValueError("input: this page holds no seat (play first)")
                        if not seat.playing:  # the match just ended: the page learns it from the final message
                            continue
                        seat.set_controls(request.get("c"))
                        await ws.send(pack_message({"type": "ack", "n": request.get("n")}))
                        continue
                    if op in ("watch", "replay", "league_replay", "stop", "play", "leave"):
                        stop_following()
                    if op in ("play", "leave") and seat is not None:
                        seat.leave()
                        self._seats.discard(seat)
                        seat = None
                    if op == "play":
                        seat = await self._take_seat(request)
                        join = seat.join_info
                        await ws.send(pack_message({"type": "seat", "match": join.match, "slot": join.slot,
                                                    "status": join.status, "decision_ticks": join.decision_ticks}))
                        feed = await self._get_feed()
                        follower = await asyncio.to_thread(feed.follow, "match", join.match)
                        follow = (asyncio.create_task(self._pump(ws, follower, "match", join.match,
                                                                 PLAYER_STATES_PER_S)), follower)
                    elif op == "leave":
                        await ws.send(pack_message({"type": "seat", "match": None, "slot": None}))
                    elif op == "list":
                        await ws.send(pack_message(await self._list()))
                    elif op == "watch":
                        kind, source_id = request.get("kind"), request.get("id")
                        if kind not in SOURCE_KINDS:
                            raise ValueError(f"kind: {kind!r} is not one of {list(SOURCE_KINDS)}")
                        feed = await self._get_feed()
                        if feed is None:
                            raise ValueError(f"zenoh: no match server reachable ({self._feed_error})")
                        follower = await asyncio.to_thread(feed.follow, kind, source_id)
                        follow = (asyncio.create_task(self._pump(ws, follower, kind, source_id)), follower)
                    elif op == "replay":
                        reply = await asyncio.to_thread(self.library.open, request.get("id"))
                        await ws.send(pack_message(reply))
                    elif op == "league_replay":
                        if self.league is None:
                            raise ValueError("league_replay: this page server shows no league (--league LEAGUE.yaml)")
                        path, same_score = await asyncio.to_thread(self.league.replay, request.get("key"))
                        reply = await asyncio.to_thread(self.library.open,
                                                        f"{self.league.replay_dir.name}/{path.name}")
                        await ws.send(pack_message({**reply, "league": {"key": request.get("key"),
                                                                        "same_score": same_score}}))
                except (ValueError, json.JSONDecodeError) as e:
                    await ws.send(pack_message({"type": "error", "error": str(e)}))
        finally:
            stop_following()
            if seat is not None:
                seat.leave()
                self._seats.discard(seat)

    async def _pump(self, ws, follower, kind: str, source_id: str, max_rate: float | None = None) -> None:
        """Send the newest state as soon as it arrives, at most ``max_rate`` (default: the page server's) times a
        second (never two within one period), with every event since the last one."""
        period = 1.0 / (max_rate or self.max_rate)
        loop, arrived = asyncio.get_running_loop(), asyncio.Event()

        def on_arrival() -> None:  # Zenoh's thread
            try:
                loop.call_soon_threadsafe(arrived.set)
            except RuntimeError:  # the loop closed while a last sample came in
                pass
        follower.on_arrival = on_arrival
        cast_shown: dict | None = None
        agents: list[str] | None = None
        hint_at: float | None = time.monotonic() + FIRST_STATE_HINT_S  # None once a state came or the hint went
        countdown_s = kickoff_countdown_s(follower.info.get("game_config"))
        shown: tuple | None = None
        events: list[GameEvent] = []
        last_sent: float | None = None
        try:
            await ws.send(pack_message({"type": "watching", "kind": kind, "id": source_id}))
            if follower.info.get("status") in ENDED_STATUSES:  # nothing more will be published: say how it ended
                await ws.send(pack_message({"type": "final", "events": [], "info": {},
                                            **{k: follower.info.get(k) for k in ("status", "summary", "result_key",
                                                                                  "error")}}))
                return
            while True:
                arrived.clear()
                update: FeedUpdate = follower.poll()
                events += update.events
                live, final = update.state, update.final
                if update.server_left and final is None and kind == "match":
                    final = await asyncio.to_thread(follower.lost_end)
                try:
                    cast = roster(live.state, live.names, countdown_s=countdown_s) if live is not None else None
                except ValueError:  # a state no match has (e.g. a car that is no blue_N/orange_N): dropped
                    live = None
                if live is None and hint_at is not None and time.monotonic() >= hint_at:
                    hint_at = None
                    await ws.send(pack_message({"type": "hint", "text": first_state_hint(kind, follower.info)}))
                if live is not None:
                    hint_at = None
                    if cast != cast_shown:  # new cars, or new names (a training run's next iteration)
                        cast_shown, agents = cast, cast["agents"]
                        await ws.send(pack_message(cast))
                    status = (live.status, live.info.get("iteration"), live.info.get("run"))
                    if status != shown:
                        shown = status
                        await ws.send(pack_message({"type": "status", "status": live.status, "info": live.info,
                                                    "scoreboard": live.scoreboard}))
                    payload = pack_message(frame(live.state, agents, events))
                    events = []
                    now = time.monotonic()
                    self.stats.add(len(payload), len(agents), None if last_sent is None else now - last_sent)
                    last_sent = now
                    await ws.send(payload)
                if final is not None:
                    final = {k: final.get(k) for k in ("status", "summary", "result_key", "info", "error")}
                    await ws.send(pack_message({"type": "final", "events": feed_events(events), **final}))
                    events = []
                    if kind == "match":
                        return
                if live is not None:  # the next frame a whole period after this one
                    await asyncio.sleep(max(0.0, period - (time.monotonic() - last_sent)))
                try:
                    await asyncio.wait_for(arrived.wait(), IDLE_LOOK_S)
                except TimeoutError:
                    pass
        except asyncio.CancelledError:
            raise
        except Exception as e:  # a closed websocket, or a bug: the follower must go either way
            if not isinstance(e, ConnectionError) and "ConnectionClosed" not in type(e).__name__:
                log.exception("web: following %s %s failed", kind, source_id)
        finally:
            follower.close()

    async def serve(self, stop: asyncio.Event, ready: Callable[["PageServer"], None] | None = None) -> None:
        from websockets.asyncio.server import serve

        async with serve(self._handler, self.host, self.port, process_request=self._process_request,
                         compression=None, max_size=MAX_REQUEST_BYTES, server_header="rocketdrl-ma-web") as server:
            self.bound_port = next(iter(server.sockets)).getsockname()[1]
            if ready is not None:
                ready(self)
            await stop.wait()
        for seat in list(self._seats):  # their threads use the feed's session: done with it before it closes
            seat.leave()
            await asyncio.to_thread(seat.wait, SEAT_STOP_S)
        if self._feed is not None:
            await asyncio.to_thread(self._feed.close)
            self._feed = None

    def url(self) -> str:
        host = self.host if ":" not in self.host else f"[{self.host}]"
        return f"http://{host}:{self.bound_port or self.port}/"


def run_page_server(server: PageServer, on_ready: Callable[[PageServer], None] | None = None) -> None:
    """Serve until SIGINT or SIGTERM."""
    import signal

    async def main() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        await server.serve(stop, on_ready)

    asyncio.run(main())

