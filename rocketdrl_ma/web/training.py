"""Watch a policy while it trains: every ``watch_every`` iterations the trainer hands the current policy (a
frozen copy: ``policies/ppo/checkpoint.ModelPolicy``) to ``TrainingBroadcast``, which plays one evaluation episode with it in a thread of its own and publishes it
at real-time pace on Zenoh, where the page (``rocketdrl-ma web``) lists the run next to the live matches.

Keys (``<server>`` as for the match server, ``<user>`` the trainer's Zenoh user, ``<run>`` the run's name)::

    rocketdrl/<server>/u/<user>/train/<run>/alive    liveliness token held while the run trains
    rocketdrl/<server>/u/<user>/train/<run>/state    each decision of the episode: the match server's state
                                                     message plus ``info`` (run, iteration)
    rocketdrl/<server>/u/<user>/train/<run>/events   events, and the episode's final message

Under the trainer's own prefix: with the server's Zenoh users and access control only that user may publish
there (every user may watch), so nobody else can show a run in its name. A member the server manages
(``rocketdrl-ma users add``) signs each message with its key instead (``server/members.py``), as Zenoh cannot
tell members apart; the page shows any other run as unverified. The session is a peer that connects to
the given endpoints (the match server's, by default), authenticated like a client on the server's machine (the
password of user ``local``, or of the client's user, from the server's folder), and listens on nothing; with no
server up it keeps retrying in the background and training never waits for it. Each
episode is also kept as a replay (``<replay_dir>/iter_<N>.npz``) the page can open later.
"""
from __future__ import annotations

import logging
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

from rocketdrl_ma.policies.base import Policy
from rocketdrl_ma.server.members import load_member_key, seal_run
from rocketdrl_ma.server.protocol import MatchStatus, encode_state, pack, pack_value
from rocketdrl_ma.validation import check_name
from rocketdrl_ma.server.settings import DEFAULT_ENDPOINT, ClientSettings, ZenohSettings

if TYPE_CHECKING:  # torch stays unimported until a training actually runs
    from rocketdrl_ma.policies.ppo.config import TrainConfig

log = logging.getLogger(__name__)


class TrainingKeys:
    """The key expressions of the training runs of one server name (see the module docstring)."""

    def __init__(self, server: str):
        self.server_root = f"rocketdrl/{check_name('server', server)}"
        self.all_alive = f"{self.server_root}/u/*/train/*/alive"

    def run_root(self, user: str, run: str) -> str:
        return f"{self.server_root}/u/{user}/train/{run}"

    def state(self, user: str, run: str) -> str:
        return f"{self.run_root(user, run)}/state"

    def events(self, user: str, run: str) -> str:
        return f"{self.run_root(user, run)}/events"

    def alive(self, user: str, run: str) -> str:
        return f"{self.run_root(user, run)}/alive"

    def parse_alive(self, key: str) -> tuple[str, str] | None:
        """``(user, run)`` of a run's liveliness key."""
        parts = key.split("/")
        if len(parts) == 7 and "/".join(parts[:2]) == self.server_root and parts[2] == "u" and parts[4] == "train" \
                and parts[6] == "alive":
            return parts[3], parts[5]
        return None


def check_run(run: object) -> str:
    """A run's name: a name without '.' (the page shows another user's run as ``<user>.<run>``)."""
    if "." in check_name("run", run):
        raise ValueError(f"run: {run!r} may not hold '.'")
    return run


class TrainingBroadcast:
    """Publishes an evaluation episode of the training policy every ``every`` iterations.

    ``due(iteration)`` says whether this iteration publishes; ``publish(iteration, policy)`` starts the
    episode (a ``Policy`` from ``policies/registry.py`` playing every car) unless the previous one is still
    playing, and returns whether it started. ``close()`` ends the episode in flight and leaves Zenoh.
    """

    def __init__(self, env_config: str | dict, run: str, every: int, *, env_overrides: dict | None = None,
                 server: str = "local", connect: tuple[str, ...] | list[str] = (DEFAULT_ENDPOINT,),
                 client: ClientSettings | None = None, replay_dir: str | Path | None = None, seed: int = 20_000,
                 speed: float = 1.0):
        """``client``: the trainer's user, password and server (default: a client of ``server`` at ``connect``,
        with the password of user ``local`` from the server's folder when it runs on this machine)."""
        if isinstance(every, bool) or not isinstance(every, int) or every < 1:
            raise ValueError(f"watch_every: expected an int >= 1 (iterations between episodes), got {every!r}")
        if not (isinstance(speed, (int, float)) and speed > 0):
            raise ValueError(f"speed: expected a number > 0, got {speed!r}")
        self.env_config, self.env_overrides = env_config, dict(env_overrides or {})
        self.run, self.every, self.seed, self.speed = check_run(run), every, seed, float(speed)
        client = client or ClientSettings.from_dict({"server": server, "zenoh": ZenohSettings(
            mode="client", connect=tuple(connect))})
        self.user, self.server, self.keys = client.user_name, client.server, TrainingKeys(client.server)
        key_path = client.user_key_path  # a member signs its run's messages
        self._run_key = load_member_key(key_path) if key_path is not None else None
        self.replay_dir = Path(replay_dir) if replay_dir is not None else None
        # a peer: unlike a client, it opens with no server up and connects once one is
        self.settings = ZenohSettings(mode="peer", listen=(), connect=client.zenoh.connect, tls=client.zenoh.tls,
                                      auth=client.zenoh.auth)
        self.session = self.settings.open()
        self._token = self.session.liveliness().declare_token(self.keys.alive(self.user, self.run))
        self._state_pub = self.session.declare_publisher(self.keys.state(self.user, self.run), express=True)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.published: list[int] = []  # iterations whose episode played to its end

    def due(self, iteration: int) -> bool:
        return iteration > 0 and iteration % self.every == 0

    def busy(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def publish(self, iteration: int, policy: Policy) -> bool:
        if self.busy() or self._stop.is_set():
            return False
        # Not a daemon: a Zenoh call on a daemon thread woken in interpreter shutdown aborts the process.
        self._thread = threading.Thread(target=self._play, args=(iteration, policy), name=f"watch-{self.run}")
        self._thread.start()
        return True

    def wait(self, timeout_s: float | None = None) -> None:
        """Until the episode in flight has been published (tests, and runs that end)."""
        if self._thread is not None:
            self._thread.join(timeout_s)

    def _play(self, iteration: int, policy: Policy) -> None:
        import rocketdrl_ma

        env = rocketdrl_ma.parallel_env(self.env_config, **self.env_overrides)
        try:
            env.reset(seed=self.seed + iteration)
            if self.replay_dir is not None:
                self.replay_dir.mkdir(parents=True, exist_ok=True)
                env.start_replay(self.replay_dir / f"iter_{iteration:06d}.npz")
            policy.reset(env.game_state)
            period_s = env.tick_skip / env.game_state.tick_rate / self.speed
            info = {"run": self.run, "iteration": iteration}
            slots = {agent: {"bot": f"{policy.name} @ iteration {iteration}", "occupant": "train"}
                     for agent in env.possible_agents}
            start, decision = time.monotonic(), 0
            while env.agents and not self._stop.is_set():
                self._send(env, decision, info, slots, done=False)
                state = env.game_state
                # the policy gives CarControls, which drive the cars as they are; it observes for itself
                env.play({agent: policy.controls(agent, state) for agent in env.agents}, observe=False)
                decision += 1
                self._stop.wait(max(0.0, start + decision * period_s - time.monotonic()))
            self._send(env, decision, info, slots, done=True)
            # The episode's end must reach the viewers (a page shows it from this message): unlike the per-decision
            # messages it may wait for a full queue, on this thread, never the trainer's.
            from zenoh import CongestionControl
            self.session.put(self.keys.events(self.user, self.run),
                             self._pack({"match": self.run, "decision": decision, "final": True, "info": info,
                                   "status": MatchStatus.STOPPED if self._stop.is_set() else MatchStatus.FINISHED,
                                   "summary": env.rules.summary()}),
                             congestion_control=CongestionControl.BLOCK)
            if not self._stop.is_set():
                self.published.append(iteration)
        except Exception:  # a broken evaluation must not take the training down
            log.exception("watch: the evaluation episode of iteration %d failed", iteration)
        finally:
            env.close()

    def _send(self, env, decision: int, info: dict, slots: dict, done: bool) -> None:
        state = env.game_state
        common = {"match": self.run, "decision": decision, "scoreboard": env.rules.scoreboard(), "done": done}
        self._state_pub.put(self._pack({**common, "status": MatchStatus.FINISHED if done else MatchStatus.RUNNING, "info": info,
                                  "slots": slots, "state": encode_state(state)}))
        if state.events:
            events = [event.as_dict() for event in state.events]
            self.session.put(self.keys.events(self.user, self.run),
                             self._pack({**common, "events": events, "info": info}))

    def _pack(self, message: dict) -> bytes:
        if self._run_key is None:
            return pack(message)
        return seal_run(self._run_key, self.server, self.user, self.run, pack_value(message))

    def close(self) -> None:
        self._stop.set()
        self.wait()
        for declared in (self._state_pub, self._token):
            try:
                declared.undeclare()
            except Exception:
                pass
        self.session.close()


def broadcast_from_train_config(cfg: TrainConfig, run_dir: str | Path) -> TrainingBroadcast | None:
    """The trainer's broadcast for a validated training config (``watch_every`` 0: none)."""
    if not cfg.watch_every:
        return None
    run_dir = Path(run_dir)
    run = "".join(c if c.isalnum() or c in "_-" else "-" for c in run_dir.resolve().name)[:64] or "run"
    return TrainingBroadcast(cfg.env, run, cfg.watch_every, env_overrides=cfg.env_overrides,
                             server=cfg.watch_server, connect=cfg.watch_connect or (DEFAULT_ENDPOINT,),
                             replay_dir=run_dir / "watch", seed=cfg.seed + 20_000)
