"""``rocketdrl-ma serve | bot | watch | lobby | router | keys | users``.

The standard library at the top only, so that ``--help`` stays fast."""
from __future__ import annotations

import argparse
import json
import sys

DEFAULT_CONNECT = "tcp/127.0.0.1:7447"


def _clean_errors(run):
    """Bad input and server refusals end the command with one line, not a traceback."""
    def wrapped(args: argparse.Namespace) -> int:
        from rocketdrl_ma.server.bot import ServerError, ServerGone
        try:
            return run(args)
        except (ValueError, ServerError, ServerGone, TimeoutError) as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
    return wrapped


def _client_settings(args: argparse.Namespace):
    """A ``ClientSettings`` from ``--config`` (a client YAML) and the flags that override it."""
    from rocketdrl_ma.server.settings import ClientSettings, ZenohSettings
    fields = {"server": args.server, "server_key": args.server_key, "user": args.user,
              "admin_secret_file": getattr(args, "admin_secret_file", None), "key_dir": args.key_dir}
    fields = {k: v for k, v in fields.items() if v is not None}
    if args.config:
        client = ClientSettings.load(args.config, **fields)
        return client.replace(zenoh=client.zenoh.with_overrides(connect=args.connect)) if args.connect else client
    return ClientSettings.from_dict({"zenoh": ZenohSettings(mode="client", connect=tuple(args.connect or
                                                                                       [DEFAULT_CONNECT])),
                                     **fields})


def _add_client_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--server", default=None, help="the server's name (rocketdrl/<server>/...; default local)")
    p.add_argument("--config", default=None, help="a client YAML (e.g. server/client.yaml, or one written by "
                                                  "`rocketdrl-ma keys`): zenoh, user, server_key")
    p.add_argument("--connect", action="append", default=None,
                   help=f"Zenoh endpoint of the server or router (client mode; default {DEFAULT_CONNECT})")
    p.add_argument("--server-key", default=None,
                   help="the server's public key to pin (ed25519:..., printed by `rocketdrl-ma serve`)")
    p.add_argument("--user", default=None, help="this client's user (default: its Zenoh user, else local if the "
                                                "server's folder holds its password, else guest)")
    p.add_argument("--key-dir", default=None,
                   help="where a server on this machine keeps server.pub, admin.secret and users.txt (the "
                        "passwords of its users) (default runs/server/<server>)")


def _run_serve(args: argparse.Namespace) -> int:
    import logging
    import signal
    import threading

    from rocketdrl_ma.server.lobby import MatchServer
    from rocketdrl_ma.server.settings import ServerSettings

    logging.basicConfig(level=getattr(logging, args.log_level.upper()), format="%(asctime)s %(name)s %(message)s")
    settings = ServerSettings.load(args.config)
    if args.name or args.key_dir:
        changes = {k: v for k, v in (("name", args.name), ("key_dir", args.key_dir)) if v}
        settings = ServerSettings.from_dict({**_settings_dict(settings), **changes})
    if args.listen or args.connect:
        settings = ServerSettings.from_dict({**_settings_dict(settings),
                                             "zenoh": settings.zenoh.with_overrides(args.listen, args.connect)})
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    with MatchServer(settings, results_path=args.results) as server:
        endpoints = ", ".join(settings.zenoh.listen_endpoints()) or "(none)"
        print(f"serving {settings.name!r}: {settings.zenoh.mode} listening on {endpoints}, "
              f"connected to {list(settings.zenoh.connect)}; results in {server.store.path}", flush=True)
        access = (f"Zenoh users {sorted(settings.access.roles)} (passwords in {settings.users_path}), access "
                  "control on" if settings.access.enabled else "OPEN MODE")
        print(f"server key {server.identity.public_text} (clients pin it with --server-key); admin secret in "
              f"{settings.keys_path / 'admin.secret'}; {access}", flush=True)
        if not settings.access.enabled:
            print("WARNING: OPEN MODE, for demos only: no Zenoh authentication. Any process that reaches "
                  f"{endpoints} may read all the traffic and play open matches, by any user name; seats are "
                  "only for members (`rocketdrl-ma users add`), whose requests are signed. server/local.yaml "
                  "authenticates every connection.", file=sys.stderr, flush=True)
        for match in list(server.matches.values()):  # the config's own matches: their tickets, for the operator
            if match.tickets:
                path = write_tickets(settings.keys_path, match.id, match.tickets)
                print(f"match {match.id}: tickets in {path} (readable by this OS user only)", flush=True)
        stop.wait()
    return 0


def write_tickets(key_dir, match: str, tickets: dict) -> str:
    """``<key_dir>/tickets/<match>.txt``: one ``slot ticket`` line each, readable by this OS user only."""
    from pathlib import Path

    from rocketdrl_ma.server.crypto import write_private
    path = Path(key_dir) / "tickets" / f"{match}.txt"
    path.unlink(missing_ok=True)  # a match id used again: its new tickets
    write_private(path, "".join(f"{slot} {ticket}\n" for slot, ticket in tickets.items()).encode())
    return str(path)


def _settings_dict(settings) -> dict:
    from dataclasses import fields
    return {f.name: getattr(settings, f.name) for f in fields(settings)}


def _run_bot(args: argparse.Namespace) -> int:
    from rocketdrl_ma.server.bot import PolicyBot

    from rocketdrl_ma.server.client import read_ticket
    from rocketdrl_ma.server.crypto import write_private

    bot = PolicyBot(args.policy, name=args.name)
    client = _client_settings(args)

    def joined(join) -> None:
        path = client.keys_path / "rejoin" / f"{join.match}.{join.slot}"
        path.unlink(missing_ok=True)  # a rejoin gets new keys: the old token is spent
        write_private(path, (join.rejoin_token + "\n").encode())
        shown = f" ({join.rejoin_token})" if args.print_secrets else ""
        print(f"joined match {join.match} as {join.slot} (status {join.status}); after a crash, rejoin with "
              f"--rejoin {path}{shown}", flush=True)

    ticket = read_ticket(args.ticket, args.slot) if args.ticket else None
    report = bot.run(args.match, args.slot, client=client, ticket=ticket, rejoin=args.rejoin, on_joined=joined)
    score = (report.summary or {}).get("score", {})
    print(f"match {report.match} {report.reason}: blue {score.get('blue')} - {score.get('orange')} orange; "
          f"{report.decisions} actions sent by {report.slot}" +
          (f"; {len(report.errors)} refused (last: {report.errors[-1]})" if report.errors else "") +
          (f"; dropped {dict(report.dropped)}" if report.dropped else ""), flush=True)
    return 0


def _run_watch(args: argparse.Namespace) -> int:
    from rocketdrl_ma.server.watch import watch

    final = watch(args.match, client=_client_settings(args), video=args.video, replay=args.replay,
                  live=not args.no_live, timeout_s=args.timeout)
    summary = final.summary or {}
    print(f"match {args.match} {final.status}: score {json.dumps(summary.get('score'))}; "
          f"result {final.result_key}" + (f"; video {args.video}" if args.video else ""), flush=True)
    return 0


def parse_set(items: list[str] | None) -> dict:
    """``--set KEY=VALUE`` items as config overrides (each value read as YAML); ``play`` takes them too."""
    import yaml
    overrides = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ValueError(f"--set: expected KEY=VALUE, got {item!r}")
        overrides[key] = yaml.safe_load(value)
    return overrides


def _parse_seats(items: list[str] | None) -> dict:
    seats = {}
    for item in items or []:
        slot, sep, user = item.partition("=")
        if not sep or not slot or not user:
            raise ValueError(f"--seat: expected SLOT=USER, got {item!r}")
        seats[slot] = user
    return seats


def _run_lobby(args: argparse.Namespace) -> int:
    from rocketdrl_ma.server.client import LobbyClient

    if args.action != "list" and not args.target:
        raise ValueError(f"lobby {args.action}: needs a {'config name' if args.action == 'create' else 'match id'}")
    client = _client_settings(args)
    session = client.zenoh.open()
    try:
        lobby = LobbyClient(session, client)
        if args.action == "create":
            options = {k: v for k, v in (("mode", args.mode), ("deadline_ms", args.deadline_ms),
                                         ("replacement", args.replacement), ("ready_timeout_s", args.ready_timeout),
                                         ("fill", args.fill), ("seed", args.seed), ("open", args.open or None))
                       if v is not None}
            if args.seat:
                options["seats"] = _parse_seats(args.seat)
            reply = lobby.create(args.target, args.id, overrides=parse_set(args.set), **options)
            print(f"created match {reply['id']} ({reply['mode']}, slots {list(reply['slot_status'])})")
            if reply["tickets"]:
                print(f"tickets in {write_tickets(client.keys_path, reply['id'], reply['tickets'])} (readable by "
                      "you only): hand each bot its own, e.g. `rocketdrl-ma bot --ticket FILE --slot SLOT`")
            for slot, ticket in reply["tickets"].items() if args.print_tickets else ():
                print(f"ticket {slot} {ticket}")
        elif args.action == "list":
            for m in lobby.list():
                print(f"{m['id']:12s} {m['status']:9s} {m['mode']:9s} {m['config']}  joined {m['joined']}/"
                      f"{m['slots']}  decision {m['decision']}  score {m['score']}")
        elif args.action == "inspect":
            print(json.dumps(lobby.inspect(args.target), indent=2, default=str))
        else:
            lobby.stop(args.target)
            print(f"stopping match {args.target}")
    finally:
        session.close()
    return 0


def _run_router(args: argparse.Namespace) -> int:
    from rocketdrl_ma.server.router import RouterSettings, run_router

    settings = RouterSettings.load(args.config)
    run_router(settings, ready=lambda s: print(f"router listening on {list(settings.zenoh.listen_endpoints())}"
                                               f"{'; access control for server ' + repr(settings.server_name) if settings.server_name else ''}",
                                               flush=True))
    return 0


def _run_keys(args: argparse.Namespace) -> int:
    from rocketdrl_ma.server.keygen import make_keys

    for line in make_keys(args.config, tls_hosts=args.tls_host, connect=args.connect, clients_dir=args.clients):
        print(line, flush=True)
    return 0


def _run_users(args: argparse.Namespace) -> int:
    from pathlib import Path

    from rocketdrl_ma.server.members import MEMBERS_FILE, add_member, read_members, remove_member
    from rocketdrl_ma.server.settings import SERVER_USER, ServerSettings

    settings = ServerSettings.load(args.config)
    key_dir = args.key_dir or settings.keys_path
    if args.action == "list":
        register = Path(key_dir) / MEMBERS_FILE
        for member in (read_members(register) if register.is_file() else {}).values():
            print(f"{member.name} {member.role}")
        return 0
    if not args.name:
        raise ValueError(f"users {args.action}: name the user")
    if args.action == "remove":
        remove_member(key_dir, args.name)
        print(f"removed {args.name}: the server refuses its key from its next request on", flush=True)
        return 0
    path = add_member(key_dir, args.name, args.role, reserved=(*settings.access.roles, SERVER_USER))
    print(f"added {args.name} ({args.role}); its key: {path} (keep it private; its clients sign with it: "
          f"--user {args.name}, found there on this machine, or user_key_file in a client YAML). The running "
          "server accepts it now", flush=True)
    return 0


def add_commands(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("serve", help="run a Zenoh match server (lobby, matches, results)")
    p.add_argument("config", help="server YAML, e.g. server/local.yaml")
    p.add_argument("--listen", action="append", default=None, help="replace the listen endpoints")
    p.add_argument("--connect", action="append", default=None, help="replace the connect endpoints")
    p.add_argument("--name", default=None, help="replace the server name")
    p.add_argument("--results", default=None, help="replace the results store path")
    p.add_argument("--key-dir", default=None, help="replace the folder of the server's key and admin secret")
    p.add_argument("--log-level", default="info")
    p.set_defaults(run=_clean_errors(_run_serve))

    b = sub.add_parser("bot", help="play a match on a server with a policy (scripted:NAME, checkpoint:PATH)")
    b.add_argument("--policy", required=True, help="a load_policy spec, e.g. scripted:ball_chaser")
    b.add_argument("--match", required=True)
    b.add_argument("--slot", default=None, help="e.g. blue_0 (default: any open slot)")
    b.add_argument("--ticket", default=None, help="the slot's ticket from the match's creator (hex), or the tickets "
                                                  "file `lobby create` wrote (with --slot)")
    b.add_argument("--rejoin", default=None, help="the rejoin token file the bot wrote when it joined (or the "
                                                  "SLOT:KEY token itself): take that slot back")
    b.add_argument("--print-secrets", action="store_true", help="also print the rejoin token (it is written to a "
                                                                "private file either way)")
    b.add_argument("--name", default=None, help="the bot's name (default: the policy spec)")
    _add_client_options(b)
    b.set_defaults(run=_clean_errors(_run_bot))

    w = sub.add_parser("watch", help="live scoreboard of a match; optionally save a replay and a video")
    w.add_argument("match")
    w.add_argument("--video", default=None, help="write an mp4 or gif of the match (from the published states)")
    w.add_argument("--replay", default=None, help="write the published states as a replay (.npz)")
    w.add_argument("--no-live", action="store_true", help="no live table, only the final line")
    w.add_argument("--timeout", type=float, default=None, help="give up after this many seconds")
    _add_client_options(w)
    w.set_defaults(run=_clean_errors(_run_watch))

    lo = sub.add_parser("lobby", help="create, list, inspect or stop matches on a server")
    lo.add_argument("action", choices=["create", "list", "inspect", "stop"])
    lo.add_argument("target", nargs="?", default=None, help="create: a config name (matches/2v2.yaml); "
                                                            "inspect/stop: a match id")
    lo.add_argument("--id", default=None, help="create: the match id (default: random)")
    lo.add_argument("--mode", choices=["lockstep", "realtime"], default=None)
    lo.add_argument("--deadline-ms", type=float, default=None)
    lo.add_argument("--replacement", choices=["repeat", "neutral"], default=None)
    lo.add_argument("--ready-timeout", type=float, default=None)
    lo.add_argument("--fill", default=None, help="policy spec for empty slots, or idle")
    lo.add_argument("--seed", type=int, default=None)
    lo.add_argument("--set", action="append", default=None, help="config override KEY=VALUE (YAML value)")
    lo.add_argument("--open", action="store_true", help="create: any player may join an empty slot (no tickets)")
    lo.add_argument("--seat", action="append", default=None, help="create: SLOT=USER, a slot only USER may join "
                                                                   "(authenticated servers only)")
    lo.add_argument("--print-tickets", action="store_true",
                    help="create: also print the tickets (they are written to <key-dir>/tickets/<id>.txt either way)")
    lo.add_argument("--admin-secret-file", default=None,
                    help="the server's admin secret, for create and stop (default <key-dir>/admin.secret)")
    _add_client_options(lo)
    lo.set_defaults(run=_clean_errors(_run_lobby))

    r = sub.add_parser("router", help="run a Zenoh router from Python (for play across machines)")
    r.add_argument("config", help="a router YAML (zenoh: section in router mode; serves: the server YAML whose "
                                  "users and access control it enforces), e.g. server/router.yaml")
    r.set_defaults(run=_clean_errors(_run_router))

    k = sub.add_parser("keys", help="make what a server config names but lacks: its key, admin secret, users "
                                    "and passwords, TLS certificates, and one client YAML per user")
    k.add_argument("config", help="a server YAML, e.g. server/lan.yaml")
    k.add_argument("--tls-host", action="append", default=None,
                   help="a host name or IP address clients reach the server (or router) by, for its certificate "
                        "(default: the hosts of the config's listen/connect endpoints)")
    k.add_argument("--connect", action="append", default=None,
                   help="the endpoint written into the client YAMLs (default: the config's TLS listen endpoints)")
    k.add_argument("--clients", default=None, help="folder for the client YAMLs (default <key_dir>/clients)")
    k.set_defaults(run=_clean_errors(_run_keys))

    u = sub.add_parser("users", help="add, remove or list the members a server manages (no restart needed)")
    u.add_argument("action", choices=["add", "remove", "list"])
    u.add_argument("name", nargs="?", default=None, help="the member's user name")
    u.add_argument("--role", choices=["admin", "player", "spectator"], default="player")
    u.add_argument("--config", default="server/local.yaml", help="the server YAML (default server/local.yaml)")
    u.add_argument("--key-dir", default=None, help="replace the server's key folder")
    u.set_defaults(run=_clean_errors(_run_users))
