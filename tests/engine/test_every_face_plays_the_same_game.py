"""Every face plays the same game: from one config and seed, with the same scripted bots, the engine itself, the
PettingZoo env, a game of a VectorEnv, a lockstep match on the match server (the bots remote, over Zenoh) and a league
match go through the same states, tick for tick (one physics tick a decision; each state hashed as the server puts it
on the wire, with the league's ``sha256_of``)."""
from __future__ import annotations

import threading

import numpy as np
from ports import free_port

import rocketdrl_ma
from rocketdrl_ma.engine import GameEngine, float32_controls
from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.league.config import load_league_config
from rocketdrl_ma.league.digest import sha256_of
from rocketdrl_ma.league.play import LocalMatch
from rocketdrl_ma.league.schedule import ScheduledMatch
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.rules.state import GameState
from rocketdrl_ma.server.bot import PolicyBot
from rocketdrl_ma.server.client import LobbyClient
from rocketdrl_ma.server.lobby import MatchServer
from rocketdrl_ma.server.protocol import encode_state
from rocketdrl_ma.server.settings import ClientSettings, ServerSettings, ZenohSettings

CONFIG = "matches/1v1.yaml"
#: one physics tick a decision, a 2 s match (and at most 1 s of overtime) from a kickoff without the countdown
OVERRIDES = {"tick_skip": 1, "clock_s": 2.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0}
SEED = 1234
BOTS = {"blue_0": "scripted:ball_chaser", "orange_0": "scripted:goalie"}


def digest(state: GameState) -> str:
    return sha256_of(encode_state(state))


def bots() -> dict:
    return {agent: load_policy(spec) for agent, spec in BOTS.items()}


def controls_of(policies: dict, state: GameState, agents) -> dict:
    # at the resolution a remote bot's action arrives in (float32), as every face gives scripted controls
    return float32_controls({agent: policies[agent].controls(agent, state) for agent in agents})


def engine_face() -> list[str]:
    config = rocketdrl_ma.parallel_env(CONFIG, **OVERRIDES).config
    engine = GameEngine.from_config(config, n_games=1)
    policies = bots()
    state = engine.reset_game(0, SEED)
    for policy in policies.values():
        policy.reset(state)
    rules, digests = engine.games[0], [digest(state)]
    while not (rules.is_terminated() or rules.is_truncated()):
        state = engine.step([controls_of(policies, state, rules.cars)])[0]
        digests.append(digest(state))
    engine.close()
    return digests


def parallel_env_face() -> list[str]:
    env = rocketdrl_ma.parallel_env(CONFIG, **OVERRIDES)
    policies = bots()
    env.reset(seed=SEED)
    for policy in policies.values():
        policy.reset(env.game_state)
    digests = [digest(env.game_state)]
    while env.agents:
        env.play(controls_of(policies, env.game_state, env.agents))
        digests.append(digest(env.game_state))
    env.close()
    return digests


def vector_env_game_face() -> list[str]:
    """Game 0 of two, the other playing its own game beside it in the same world. (A game elsewhere in the
    world's grid of arenas plays about another origin: the same game up to float rounding.)"""
    vec = VectorEnv(CONFIG, n_games=2, autoreset=False, **OVERRIDES)
    policies = [bots(), bots()]
    vec.reset(seed=SEED)
    for game, players in zip(vec.games, policies):
        for policy in players.values():
            policy.reset(game.game_state)
    digests = [digest(vec.games[0].game_state)]
    done = False
    while not done:
        _, _, terminated, truncated, _ = vec.step(None, [controls_of(players, game.game_state, game.agents)
                                                         for game, players in zip(vec.games, policies)])
        digests.append(digest(vec.games[0].game_state))
        done = bool(terminated[0] or truncated[0])
        if (terminated | truncated)[1] and not done:
            vec.reset_games(np.array([False, True]))
    vec.close()
    return digests


def league_face() -> list[str]:
    cfg = load_league_config("leagues/replay_check.yaml", {"overrides": OVERRIDES})
    game = LocalMatch(cfg, ScheduledMatch(0, "same-game", "ball_chaser", "goalie", SEED), bots())
    digests = [digest(game.env.game_state)]
    while not game.over:
        game.step([policy.controls(agent, state) for policy, agent, state in game.cars()])
        digests.append(digest(game.env.game_state))
    game.close()
    return digests


class RecordingBot(PolicyBot):
    """A scripted bot on the match server that hashes every state it is sent."""

    def __init__(self, spec: str):
        super().__init__(spec)
        self.digests: list[str] = []

    def act(self, obs, info):
        self.digests.append(digest(info["state"]))
        return super().act(obs, info)

    def on_end(self, info: dict) -> None:
        self.digests.append(digest(info["state"]))


def server_face(tmp_path, monkeypatch) -> list[str]:
    monkeypatch.setenv("ROCKETDRL_MA_KNOWN_SERVERS", str(tmp_path / "known_servers"))
    endpoint, key_dir = f"tcp/127.0.0.1:{free_port()}", tmp_path / "keys"
    # a deadline no loaded machine misses: a missed action would be a different game
    settings = {"name": "same-game", "zenoh": {"mode": "peer", "listen": [endpoint]}, "key_dir": str(key_dir),
                "match_defaults": {"open": True}, "limits": {"max_deadline_ms": 60_000.0, "overrides": sorted(OVERRIDES)}}
    server = MatchServer(ServerSettings.from_dict(settings), results_path=str(tmp_path / "results.sqlite"))
    server.start()
    client = ClientSettings.from_dict({"server": "same-game", "key_dir": str(key_dir),
                                       "zenoh": ZenohSettings(mode="client", connect=(endpoint,))})
    session = client.zenoh.open()
    try:
        lobby = LobbyClient(session, client)
        lobby.create(CONFIG, "m", overrides=OVERRIDES, seed=SEED, mode="lockstep", deadline_ms=60_000,
                     ready_timeout_s=60)
        players = {agent: RecordingBot(spec) for agent, spec in BOTS.items()}
        errors: list[BaseException] = []

        def run(agent: str) -> None:
            try:
                players[agent].run("m", agent, client=client)
            except BaseException as e:  # reported below
                errors.append(e)
        threads = [threading.Thread(target=run, args=(agent,)) for agent in players]
        for t in threads:
            t.start()
        for t in threads:
            t.join(300)
        assert not errors, errors
        assert all(slot["missed"] == 0 for slot in lobby.inspect("m")["slot_status"].values())
        assert players["blue_0"].digests == players["orange_0"].digests
        return players["blue_0"].digests
    finally:
        session.close()
        server.close()


def test_every_face_plays_the_same_game_tick_for_tick(tmp_path, monkeypatch):
    reference = engine_face()
    assert len(reference) > 2 * 120  # the 2 s of clock, one tick a decision
    faces = {"ParallelEnv": parallel_env_face(), "VectorEnv game": vector_env_game_face(), "league": league_face(),
             "server (lockstep)": server_face(tmp_path, monkeypatch)}
    for face, digests in faces.items():
        first_difference = next((t for t, (a, b) in enumerate(zip(reference, digests)) if a != b), None)
        assert first_difference is None and len(digests) == len(reference), (
            f"{face}: {len(digests)} states against the engine's {len(reference)}; first different at decision "
            f"{first_difference}")
