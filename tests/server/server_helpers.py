"""Helpers for the match server tests: free loopback ports, servers started in-process or as
``rocketdrl-ma serve`` subprocesses, bot subprocesses, and polling helpers (no fixed sleeps)."""
from __future__ import annotations

import socket
import sys
import time
from pathlib import Path

import zenoh

from output_process import OutputProcess

from rocketdrl_ma.server.client import LobbyClient, SealedStream
from rocketdrl_ma.server.lobby import MatchServer
from rocketdrl_ma.server.settings import ClientSettings, ServerSettings, ZenohSettings

REPO = Path(__file__).resolve().parents[2]
BOTPROC = Path(__file__).with_name("botproc.py")
#: a short game for tests: 3 s of clock, no frozen kickoff, at most 1 s of overtime
SHORT = {"clock_s": 3.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0}


def free_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def wait_for(predicate, timeout_s: float = 30.0, what: str = "condition", interval_s: float = 0.05):
    """Poll ``predicate`` until it returns something truthy; fail the test after ``timeout_s``."""
    end = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(interval_s)


def server_settings(endpoint: str, name: str = "test", key_dir: Path | None = None, **extra) -> ServerSettings:
    """A loopback peer server; its matches are open unless ``match_defaults`` says otherwise."""
    extra.setdefault("match_defaults", {"open": True})
    return ServerSettings.from_dict({"name": name, "zenoh": {"mode": "peer", "listen": [endpoint]},
                                     "key_dir": str(key_dir) if key_dir else None, **extra})


def client_settings(endpoint: str, name: str, key_dir: Path, **extra) -> ClientSettings:
    return ClientSettings.from_dict({"server": name, "key_dir": str(key_dir),
                                     "zenoh": ZenohSettings(mode="client", connect=(endpoint,)), **extra})


class Running:
    """An in-process server plus a client session and lobby client talking to it (as user ``guest``, with
    the admin secret from the server's key dir)."""

    def __init__(self, tmp_path: Path, name: str = "test", endpoint: str | None = None, **extra):
        self.endpoint = endpoint or free_endpoint()
        self.name = name
        self.results = tmp_path / "results.sqlite"
        self.key_dir = tmp_path / "keys"
        self.server = MatchServer(server_settings(self.endpoint, name, self.key_dir, **extra),
                                  results_path=str(self.results))
        self.server.start()
        self.client_settings = client_settings(self.endpoint, name, self.key_dir)
        self.session = self.client_settings.zenoh.open()
        self.lobby = LobbyClient(self.session, self.client_settings)
        self._sessions: list = []

    def client(self, **extra) -> ClientSettings:
        return self.client_settings.replace(**extra)

    def lobby_as(self, user: str) -> LobbyClient:
        """A lobby client of ``user`` on a session of its own (with Zenoh users, its own authentication)."""
        client = self.client(user=user)
        session = client.zenoh.open()
        self._sessions.append(session)
        return LobbyClient(session, client)

    def close(self) -> None:
        for session in [*self._sessions, self.session]:
            session.close()
        self.server.close()

    def wait_status(self, match: str, statuses=("finished",), timeout_s: float = 60.0) -> dict:
        return wait_for(lambda: (lambda i: i if i["status"] in statuses else None)(self.lobby.inspect(match)),
                        timeout_s, f"match {match} to reach {statuses}")


def cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "rocketdrl_ma.cli", *args]


Proc = OutputProcess


class Procs:
    """Subprocesses started by a test; every one still alive is killed at teardown."""

    def __init__(self):
        self.procs: list[Proc] = []

    def start(self, argv: list[str]) -> Proc:
        p = Proc(argv)
        self.procs.append(p)
        return p

    def bot(self, running: "Running", match: str, slot: str | None = None, policy="scripted:ball_chaser",
            rejoin: str | None = None, *extra: str) -> Proc:
        argv = cli("bot", "--policy", policy, "--match", match, "--server", running.name, "--connect",
                   running.endpoint, "--key-dir", str(running.key_dir), *extra)
        argv += ["--slot", slot] if slot else []
        argv += ["--rejoin", rejoin] if rejoin else []
        return self.start(argv)

    def botproc(self, running: "Running", match: str, slots: list[str], *extra: str) -> Proc:
        return self.start([sys.executable, str(BOTPROC), "--connect", running.endpoint, "--server", running.name,
                           "--key-dir", str(running.key_dir), "--match", match, "--slots", ",".join(slots), *extra])

    def serve(self, tmp_path: Path, name: str = "test", config: str = "server/local.yaml") -> "Served":
        endpoint = free_endpoint()
        key_dir = tmp_path / "keys"
        p = self.start(cli("serve", config, "--listen", endpoint, "--name", name, "--results",
                           str(tmp_path / "results.sqlite"), "--key-dir", str(key_dir)))
        p.line("serving", 60.0)
        return Served(p, endpoint, name, key_dir)

    def kill_all(self) -> None:
        for p in self.procs:
            if p.popen.poll() is None:
                p.popen.kill()
            p.popen.wait(10)


class Served:
    """A ``rocketdrl-ma serve`` subprocess: its process, endpoint, name and key dir (like ``Running``)."""

    def __init__(self, proc: Proc, endpoint: str, name: str, key_dir: Path):
        self.proc, self.endpoint, self.name, self.key_dir = proc, endpoint, name, key_dir
        self.client_settings = client_settings(endpoint, name, key_dir)

    def client_args(self) -> list[str]:
        return ["--server", self.name, "--connect", self.endpoint, "--key-dir", str(self.key_dir)]


class RawBot:
    """A bot driven by hand over the protocol (join, liveliness, verified observations in, actions out), for
    tests that need to send exactly what they choose: late, missing, malformed or forged actions."""

    def __init__(self, session, lobby: LobbyClient, match: str, slot: str | None = None, answer=None,
                 before_alive=None, **join_fields):
        """``answer(message)`` runs on each verified observation as it arrives and may return an action to
        send at once (None: stay silent). ``before_alive(bot)`` runs once seated, before the liveliness token
        that lets the match start (e.g. to send decision 0's action ahead, free of any deadline)."""
        self.session, self._answer = session, answer
        self.join = lobby.join(match, slot, **join_fields)
        self.messages: list[dict] = []
        self.errors: list[str] = []
        keys = self.join.keys
        stream = lambda kinds: SealedStream(lobby.server_key, lobby.keys.server, match, self.join.instance,  # noqa
                                            kinds, slot=self.join.slot)
        self.obs_stream, self.error_stream = stream(("obs",)), stream(("error",))
        self._subs = [
            session.declare_subscriber(keys["obs"], self._on_obs),
            session.declare_subscriber(keys["error"], self._on_error),
        ]
        if before_alive is not None:
            before_alive(self)
        self._token = session.liveliness().declare_token(self.join.keys["alive"])

    def _on_obs(self, sample) -> None:
        message = self.obs_stream.open(sample.payload.to_bytes())
        if message is None:
            return
        self.messages.append(message)
        action = self._answer(message) if self._answer is not None and not message["done"] else None
        if action is not None:
            self.send(action, message["decision"])

    def _on_error(self, sample) -> None:
        message = self.error_stream.open(sample.payload.to_bytes())
        if message is not None:
            self.errors.append(message["error"])

    def send(self, action, decision: int, secret: bytes | None = None, key: str | None = None,
             slot: str | None = None) -> None:
        from rocketdrl_ma.server.protocol import action_message
        # BLOCK: a test's action must reach the server (the put default, DROP, may lose it on a busy machine)
        self.session.put(key or self.join.keys["act"], action_message(
            secret or self.join.secret, self.join.match, slot or self.join.slot, decision, action),
            congestion_control=zenoh.CongestionControl.BLOCK)

    def disconnect(self) -> None:
        self._token.undeclare()
        for s in self._subs:
            s.undeclare()


HOSTILE = Path(__file__).with_name("hostile.py")
ROLES = {"ops": "admin", "alice": "player", "bob": "player", "mallory": "player", "web": "spectator"}


def write_yaml(path: Path, data: dict) -> str:
    import yaml
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return str(path)


def secure_config(tmp_path: Path, endpoint: str, name: str = "lab", mode: str = "peer", **extra) -> dict:
    """A server YAML (as a dict) with Zenoh users and access control; its files live under ``tmp_path/keys``.
    ``mode`` peer: it listens on ``endpoint`` with TLS; client: it connects to a router there."""
    keys = tmp_path / "keys"
    zenoh = ({"mode": "peer", "listen": [endpoint],
              "tls": {"listen_certificate": str(keys / "tls/cert.pem"), "listen_private_key": str(keys / "tls/key.pem")}}
             if mode == "peer" else {"mode": "client", "connect": [endpoint]})
    return {"name": name, "zenoh": zenoh, "key_dir": str(keys),
            "access": {"users_file": str(keys / "users.txt"), "roles": dict(ROLES)},
            "match_defaults": {"open": False}, **extra}


def free_tls_endpoint() -> str:
    return free_endpoint().replace("tcp/", "tls/")


class Secure:
    """An in-process server with Zenoh users, TLS and access control (the server is the peer holding the
    ACL), every file made by ``rocketdrl-ma keys``; ``client(user)`` loads that user's client YAML."""

    def __init__(self, tmp_path: Path, name: str = "lab", **extra):
        from rocketdrl_ma.server.keygen import make_keys
        self.name, self.endpoint, self.tmp_path = name, free_tls_endpoint(), tmp_path
        self.config_path = write_yaml(tmp_path / "server.yaml", secure_config(tmp_path, self.endpoint, name, **extra))
        self.made = make_keys(self.config_path, tls_hosts=["127.0.0.1"])
        self.key_dir = tmp_path / "keys"
        self.results = tmp_path / "results.sqlite"
        self.server = MatchServer(ServerSettings.load(self.config_path), results_path=str(self.results)).start()
        self.sessions: dict[str, object] = {}

    def client_file(self, user: str) -> str:
        return str(self.key_dir / "clients" / f"{user}.yaml")

    def client(self, user: str) -> ClientSettings:
        return ClientSettings.load(self.client_file(user))

    def session(self, user: str):
        if user not in self.sessions:
            self.sessions[user] = self.client(user).zenoh.open()
        return self.sessions[user]

    def lobby(self, user: str) -> LobbyClient:
        return LobbyClient(self.session(user), self.client(user))

    def close(self) -> None:
        for s in self.sessions.values():
            s.close()
        self.server.close()
