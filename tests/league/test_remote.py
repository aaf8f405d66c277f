"""A remote entrant: a `rocketdrl-ma league-bot` process plays its league matches through a real match
server on loopback (Zenoh, with users and access control, as server/local.yaml runs), and the results land in
the league's store like local ones."""
from __future__ import annotations

import socket
import subprocess
import sys
from pathlib import Path

import pytest

from rocketdrl_ma.league.config import validate_league_config
from rocketdrl_ma.league.ratings import rate
from rocketdrl_ma.league.runner import run_league
from rocketdrl_ma.league.schedule import schedule
from rocketdrl_ma.results import ResultsStore
from rocketdrl_ma.server.lobby import MatchServer
from rocketdrl_ma.server.settings import ClientSettings, ServerSettings

REPO = Path(__file__).resolve().parents[2]


def free_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


@pytest.mark.slow
def test_remote_bot_entrant_plays_through_the_server(tmp_path):
    endpoint = free_endpoint()
    key_dir = tmp_path / "keys"
    settings = ServerSettings.from_dict({"name": "leaguetest", "zenoh": {"mode": "peer", "listen": [endpoint]},
                                         "key_dir": str(key_dir),
                                         "access": {"roles": {"local": "admin", "alice": "player"}}})
    server = MatchServer(settings, results_path=str(tmp_path / "server.sqlite")).start()
    # alice's bot authenticates as alice (its password in the server's folder: the same machine here)
    bot = subprocess.Popen([sys.executable, "-m", "rocketdrl_ma.cli", "league-bot", "--entrant", "alice",
                            "--policy", "scripted:ball_chaser", "--server", "leaguetest", "--connect", endpoint,
                            "--key-dir", str(key_dir), "--max-matches", "2"], cwd=REPO, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True)
    try:
        cfg = validate_league_config({
            "name": "remote", "match": "matches/1v1.yaml", "results": str(tmp_path / "league.sqlite"),
            "overrides": {"clock_s": 4.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
            "format": "per_pair", "matches_per_pair": 2,
            "server": {"name": "leaguetest", "connect": [endpoint], "join_timeout_s": 60},
            "entrants": [{"name": "alice", "remote": True}, {"name": "idle", "policy": "scripted:idle"}]})
        # the bot process may still be starting: the first invitation waits for its queryable
        league = ClientSettings.from_dict({"server": "leaguetest", "key_dir": str(key_dir),
                                           "zenoh": {"mode": "client", "connect": [endpoint]}})
        run = run_league(cfg, client=league)
        assert run.played == 2
        out, _ = bot.communicate(timeout=60)
        assert bot.returncode == 0, out
        assert "2 matches played" in out
    finally:
        if bot.poll() is None:
            bot.kill()
            bot.wait()
        server.close()
    with ResultsStore(cfg.results) as store:
        results = store.results(source="league")
    assert sorted(r.match_key for r in results) == sorted(m.key for m in schedule(cfg))
    for r in results:
        assert r.details["where"] == "server" and r.details["server_match"].startswith("remote-")
        assert r.details["players"] in ({"blue_0": "alice", "orange_0": "idle"},
                                        {"blue_0": "idle", "orange_0": "alice"})
        assert r.duration_s >= 4.0
    with ResultsStore(tmp_path / "server.sqlite") as server_store:  # the server kept its own rows too
        assert {r.details["match_id"] for r in server_store.results()} == {r.details["server_match"] for r in results}
    table = rate(cfg, schedule(cfg), results)
    assert {r.name: r.matches for r in table.ratings} == {"alice": 2, "idle": 2}
