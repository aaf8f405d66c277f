"""``rocketdrl-ma web``: the page server (standard library at the top: ``--help`` stays fast)."""
from __future__ import annotations

import argparse
import sys


def _run_web(args: argparse.Namespace) -> int:
    from pathlib import Path

    from rocketdrl_ma.web.bridge import PageServer, is_loopback_host, run_page_server
    from rocketdrl_ma.web.feed import SpectatorFeed
    from rocketdrl_ma.web.replays import ReplayLibrary

    from .server import _client_settings

    try:
        if not is_loopback_host(args.host) and not args.allow_remote:
            raise ValueError(f"--host: {args.host!r} is not loopback; pass --allow-remote to serve the page to "
                             "other machines")
        # a client like `watch`: --config's user and pinned key, else the password and key in the server's folder
        settings = None if args.no_zenoh else _client_settings(args)
        make_feed = None if settings is None else (lambda: SpectatorFeed(settings))
        library = ReplayLibrary(args.replays if args.replays is not None else ["runs"], args.replay or [])
        league = None
        if args.league:
            import tempfile

            from rocketdrl_ma.web.league import LeagueView
            league = LeagueView(args.league, Path(tempfile.mkdtemp(prefix="league-replays-")))
            library.folders.append(league.replay_dir)
        opponents = None
        if args.play:
            from rocketdrl_ma.web.play import opponent_choices
            if settings is None:
                raise ValueError("--play: needs a match server (drop --no-zenoh)")
            for spec in args.opponent or []:
                if not spec.startswith("checkpoint:"):
                    raise ValueError(f"--opponent: expected checkpoint:PATH (scripted bots are offered anyway), "
                                     f"got {spec!r}")
            opponents = opponent_choices(args.opponent or [])
        server = PageServer(make_feed, library, host=args.host, port=args.port, max_rate=args.max_rate,
                            node_modules=Path(args.node_modules) if args.node_modules else None,
                            play_opponents=opponents, league=league)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2

    def ready(s: PageServer) -> None:
        where = "no Zenoh" if settings is None else \
            f"match server {settings.server!r} via {list(settings.zenoh.connect)} as {settings.user_name}"
        where += "; play on" if opponents is not None else ""
        where += f"; league {league.cfg.name!r} at {s.url()}league" if league is not None else ""
        print(f"page at {s.url()} ({where}; replays from {[str(f) for f in library.folders + library.files]})",
              flush=True)

    run_page_server(server, ready)
    return 0


def add_commands(sub: argparse._SubParsersAction) -> None:
    from .server import _add_client_options

    w = sub.add_parser("web", help="a page to watch live matches, replays and training runs in a browser")
    w.add_argument("--host", default="127.0.0.1", help="address to serve the page on (default loopback only)")
    w.add_argument("--port", type=int, default=8765, help="0: any free port")
    w.add_argument("--allow-remote", action="store_true", help="needed for a non-loopback --host")
    _add_client_options(w)
    w.add_argument("--no-zenoh", action="store_true", help="replays only: no match server")
    w.add_argument("--replays", action="append", default=None,
                   help="a folder whose .npz replays the page lists (repeatable; default: runs)")
    w.add_argument("--replay", action="append", default=None, help="one more replay file to list (repeatable)")
    w.add_argument("--max-rate", type=float, default=30.0, help="states per second sent to a page (at most 30)")
    w.add_argument("--play", action="store_true",
                   help="let the page play: join a real-time match's free slot, or create one against bots "
                        "(loopback only; creating needs the server's admin secret, found from its folder)")
    w.add_argument("--opponent", action="append", default=None,
                   help="a checkpoint:PATH the page may play against (repeatable; scripted bots are offered anyway)")
    w.add_argument("--league", default=None,
                   help="a league config (LEAGUE.yaml): its standings, ratings, payoff matrix and match replays, "
                        "read from the results store it names, at /league")
    w.add_argument("--node-modules", default=None, help="where `npm ci` installed three.js (default: the repo's)")
    w.set_defaults(run=_run_web)
