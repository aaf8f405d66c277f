"""``rocketdrl-ma league CONFIG``, ``league-curve`` and ``league-bot`` (standard library at the top)."""
from __future__ import annotations

import argparse


def _run_league(args: argparse.Namespace) -> int:
    from rocketdrl_ma.results import ResultsStore

    from rocketdrl_ma.league.batch_play import DEFAULT_AT_ONCE
    from rocketdrl_ma.league.config import load_league_config
    from rocketdrl_ma.league.ratings import rate
    from rocketdrl_ma.league.report import write_report
    from rocketdrl_ma.league.runner import run_league
    from rocketdrl_ma.league.schedule import schedule

    overrides = {"results": args.results} if args.results else {}
    cfg = load_league_config(args.config, overrides)
    if args.at_once is None:
        args.at_once = DEFAULT_AT_ONCE
    if args.verify:
        return _verify(cfg, args.verify, args.workers, args.at_once)
    planned = schedule(cfg)
    if not args.report_only:
        def show(match, result) -> None:
            print(f"[{match.index + 1}/{len(planned)}] {match.key}: {match.blue} {result.score_blue} - "
                  f"{result.score_orange} {match.orange} (seed {match.seed}, {result.duration_s:.0f} s)", flush=True)

        client = None
        if args.client_config:
            from rocketdrl_ma.server.settings import ClientSettings
            client = ClientSettings.load(args.client_config)
        run = run_league(cfg, max_matches=args.max_matches, on_result=show, workers=args.workers, ray=args.ray,
                         at_once=args.at_once, client=client)
        print(f"league {cfg.name}: {run.scheduled} scheduled, {run.already_stored} already stored, "
              f"{run.played} played now", flush=True)
    with ResultsStore(cfg.results) as store:
        results = store.results(source="league", key_prefix=f"{cfg.name}/")
    table = rate(cfg, planned, results)
    for i, r in enumerate(table.ratings, 1):
        print(f"{i:2d}. {r.name:24s} mu {r.mu:6.2f}  sigma {r.sigma:5.2f}  ordinal {r.ordinal:6.2f}  "
              f"W-D-L {r.wins}-{r.draws}-{r.losses}")
    print(f"report: {write_report(cfg, table, len(planned), args.config, args.report, results)}")
    if args.record:
        from rocketdrl_ma.league.replay_check import write_records
        print(f"records: {write_records(cfg, results, args.record)}")
    return 0


def _verify(cfg, path: str, workers: int, at_once: int) -> int:
    from rocketdrl_ma.league.replay_check import read_records, verify_records

    differences = verify_records(cfg, path, workers, at_once)
    for line in differences:
        print(f"DIFFERS {line}")
    matches, _ = read_records(path)
    print(f"league {cfg.name}: {len(matches)} recorded matches replayed; "
          + (f"{len(differences)} differences" if differences else "every field identical, bit for bit"))
    return 1 if differences else 0


def _run_curve(args: argparse.Namespace) -> int:
    import time
    from pathlib import Path

    from rocketdrl_ma.league.batch_play import DEFAULT_AT_ONCE
    from rocketdrl_ma.league.curve import (pin_anchors, play_snapshots, rating_curve, read_snapshot, run_snapshots,
                                           write_curve_json)
    from rocketdrl_ma.league.curve_config import load_curve_config
    from rocketdrl_ma.league.curve_plot import plot_curve, write_tensorboard
    from rocketdrl_ma.results import ResultsStore

    cfg = load_curve_config(args.config)
    at_once = DEFAULT_AT_ONCE if args.at_once is None else args.at_once
    if args.pin_anchors:
        out = Path(args.out or f"runs/league/{cfg.name}-anchors")
        with ResultsStore(out / "results.sqlite") as store:
            pinned = pin_anchors(cfg, store, out, args.workers, at_once)
        print(f"anchors:  # pinned by `rocketdrl-ma league-curve {args.config} --pin-anchors`")
        for a in cfg.anchors:
            mu, sigma = pinned[a.name]
            print(f'  - {{name: {a.name}, policy: "{a.policy}", mu: {mu:.2f}, sigma: {sigma:.2f}}}')
        return 0
    if (args.run_dir is None) == (not args.checkpoints):
        raise SystemExit("league-curve: give a training run (--run-dir DIR) or checkpoints "
                         "(--checkpoints A.pt B.pt ...)")
    if args.checkpoints and not args.out:
        raise SystemExit("league-curve: --checkpoints needs --out DIR (where the results and the curve go)")
    out = Path(args.out) if args.out else Path(args.run_dir) / "rating_curve"
    title = f"{cfg.name}: {Path(args.run_dir).name if args.run_dir else 'checkpoints'}"

    def show(match, result) -> None:
        print(f"{match.key}: {match.blue} {result.score_blue} - {result.score_orange} {match.orange}", flush=True)

    with ResultsStore(out / "results.sqlite") as store:
        rated: list = []
        trainer_gone = False
        while True:
            snapshots = (run_snapshots(Path(args.run_dir), args.final) if args.run_dir
                         else [read_snapshot(Path(p)) for p in args.checkpoints])
            play_snapshots(cfg, snapshots, store, out, args.workers, at_once, on_result=show)
            points = rating_curve(cfg, snapshots, store)
            if points != rated:
                rated = points
                write_curve_json(points, out / "curve.json")
                plot_curve(cfg, points, out / "curve.png", title)
                write_tensorboard(points, out / "tensorboard")
                for p in points:
                    vs = "  ".join(f"{name} {share:.2f}" for name, share in p.points.items())
                    print(f"{p.snapshot:>16} {p.agent_steps:>12,} steps  rating {p.mu:6.2f} "
                          f"[{p.low:6.2f}, {p.high:6.2f}]  points/match: {vs}", flush=True)
                print(f"curve: {out / 'curve.png'}, {out / 'curve.json'}, TensorBoard {out / 'tensorboard'}",
                      flush=True)
            if not args.follow or any(s.name == "final" for s in snapshots) or trainer_gone:
                return 0
            time.sleep(args.poll_s)
            # a training that died writes no final checkpoint: rate what it left, once more, then stop
            trainer_gone = args.follow_pid is not None and not _alive(args.follow_pid)


def _alive(pid: int) -> bool:
    import os

    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process of that number: alive, only not ours to signal
        pass
    return True


def _run_league_bot(args: argparse.Namespace) -> int:
    from rocketdrl_ma.server.bot import PolicyBot

    from rocketdrl_ma.validation import check_name
    from rocketdrl_ma.league.remote import serve_invitations
    from .server import _client_settings

    entrant = check_name("entrant", args.entrant)
    args.user = args.user or (None if args.config else entrant)  # the entrant's user unless its YAML names one
    client = _client_settings(args)
    if client.user_name != entrant:
        raise ValueError(f"--entrant {entrant!r}: the league seats it as user {entrant!r}, but this client is "
                         f"user {client.user_name!r}")
    session = client.zenoh.open()
    print(f"league bot {entrant} ({args.policy}) waiting for invitations from server {client.server!r}", flush=True)
    try:
        played = serve_invitations(session, client.server, entrant, lambda: PolicyBot(args.policy, name=entrant),
                                   max_matches=args.max_matches, client=client,
                                   on_match=lambda m, reports: print(f"played {m}", flush=True))
    finally:
        session.close()
    print(f"league bot {entrant}: {played} matches played")
    return 0


def add_commands(sub: argparse._SubParsersAction) -> None:
    from .server import _add_client_options, _clean_errors

    p = sub.add_parser("league", help="play a league (e.g. leagues/main.yaml): ratings, payoff matrix, report")
    p.add_argument("config", help="league YAML, e.g. leagues/main.yaml")
    p.add_argument("--results", default=None, help="replace the config's results store (SQLite)")
    p.add_argument("--report", default=None, help="replace the config's report folder")
    p.add_argument("--max-matches", type=int, default=None, help="play at most this many missing matches")
    p.add_argument("--report-only", action="store_true", help="rate the stored matches, play none")
    p.add_argument("--client-config", default=None,
                   help="remote entrants: a client YAML for the match server (an admin's, from `rocketdrl-ma keys`); "
                        "default: the password and key in the server's folder on this machine")
    p.add_argument("--workers", type=int, default=0,
                   help="share the local matches among this many processes (default 0: all in this process); "
                        "results and ratings are the same either way")
    p.add_argument("--at-once", type=int, default=None, metavar="N",
                   help="local matches each process plays at once, every checkpoint's cars of all of them in one "
                        "forward (default 8; 1: one match at a time); results and ratings are the same either way")
    p.add_argument("--ray", default=None, metavar="auto|HOST:PORT",
                   help="play local matches as tasks on a Ray cluster (`pip install rocketdrl-ma[cluster]`)")
    p.add_argument("--record", default=None, metavar="FILE",
                   help="also write the stored matches as replay records (seed, sides, score, ticks, digests of the "
                        "final physics state and the events) and their ratings, as JSON lines")
    p.add_argument("--verify", default=None, metavar="FILE",
                   help="play every match recorded in FILE again (no results store) and compare every field and "
                        "the ratings bit for bit; exit status 1 if anything differs")
    p.set_defaults(run=_run_league)
    c = sub.add_parser("league-curve", help="a training run's rating curve: every snapshot against pinned anchors")
    c.add_argument("config", help="curve YAML, e.g. leagues/curve_2v2.yaml")
    c.add_argument("--run-dir", default=None, help="a training run's folder (its snapshots/ and final.pt)")
    c.add_argument("--checkpoints", nargs="+", default=None, metavar="PT", help="rate these checkpoints instead")
    c.add_argument("--out", default=None,
                   help="where the results store, curve.json, curve.png and the TensorBoard events go "
                        "(default: RUN_DIR/rating_curve)")
    c.add_argument("--follow", action="store_true",
                   help="keep rating the run's new snapshots as training writes them, until its final.pt is rated")
    c.add_argument("--poll-s", type=float, default=60.0, help="--follow: seconds between looks for new snapshots")
    c.add_argument("--final", default=None, metavar="PT",
                   help="the run's final checkpoint, the curve's last point (default RUN_DIR/final.pt)")
    c.add_argument("--follow-pid", type=int, default=None, metavar="PID",
                   help="--follow: the training's process; once it is gone, rate what it left and stop")
    c.add_argument("--pin-anchors", action="store_true",
                   help="play the anchors' round robin and print their ratings to pin in the config")
    c.add_argument("--workers", type=int, default=0, help="share the matches among this many processes")
    c.add_argument("--at-once", type=int, default=None, metavar="N", help="matches each process plays at once")
    c.set_defaults(run=_run_curve)
    b = sub.add_parser("league-bot", help="a remote league entrant: wait for invitations, play them on the server")
    b.add_argument("--entrant", required=True, help="the entrant's name in the league YAML (remote: true)")
    b.add_argument("--policy", required=True, help="a load_policy spec, e.g. checkpoint:PATH")
    b.add_argument("--max-matches", type=int, default=None, help="stop after this many matches")
    _add_client_options(b)  # --config: the entrant's client YAML (its user and password, the server's key)
    b.set_defaults(run=_clean_errors(_run_league_bot))
