"""The wire protocol page (docs/guides/wire-protocol.md) is enough to write a bot: ``readme_bot.py`` (msgpack,
zenoh and cryptography only; no import of rocketdrl_ma) joins with a ticket, plays a full lockstep match against an
SDK bot, and its actions drive its car."""
from __future__ import annotations

import sys
import threading
from pathlib import Path

from server_helpers import SHORT

from rocketdrl_ma.results import ResultsStore
from rocketdrl_ma.server import PolicyBot, Spectator
from rocketdrl_ma.server.spectator import StateUpdate

README_BOT = Path(__file__).with_name("readme_bot.py")


def test_a_bot_written_from_the_readme_plays_a_match(running, procs):
    # the longest deadline: lockstep moves on as soon as both actions are in, and on a loaded machine (two busy
    # loops beside the suite) a 50 ms one counted some of this bot's correct actions late
    created = running.lobby.create("matches/1v1.yaml", "readme", overrides={**SHORT, "clock_s": 5.0},
                                   ready_timeout_s=120, open=False, deadline_ms=2000)
    server_key = (running.key_dir / "server.pub").read_text().strip()
    spectator = Spectator("readme", client=running.client_settings).open()
    bot = procs.start([sys.executable, str(README_BOT), "--connect", running.endpoint, "--server", "test",
                       "--match", "readme", "--server-key", server_key, "--slot", "blue_0",
                       "--ticket", created["tickets"]["blue_0"]])
    assert bot.line("joined blue_0", 60)
    opponent = threading.Thread(target=lambda: PolicyBot("scripted:goalie").run(
        "readme", "orange_0", client=running.client_settings, ticket=created["tickets"]["orange_0"]))
    opponent.start()
    updates = list(spectator.updates(timeout_s=120))
    spectator.close()
    opponent.join(60)
    assert bot.wait(60) == 0, bot.output()
    info = running.wait_status("readme")
    reason, decisions, dropped = bot.line("done ").split()[1:]
    assert reason == "finished" and int(dropped) == 0
    slot = info["slot_status"]["blue_0"]
    assert slot["bot"] == "readme-bot" and slot["received"] == int(decisions) >= 0.9 * info["decision"]
    assert info["rejected"] == {}  # every action it sent was well formed, MAC'd and on time
    # its actions drove the car: full throttle in every state after its first answer, steering that varies
    states = [u for u in updates if isinstance(u, StateUpdate) and u.decision >= 2]
    controls = [u.state.last_controls["blue_0"] for u in states]
    assert controls and all(c.throttle == 1.0 for c in controls) and len({c.steer for c in controls}) > 1
    [result] = ResultsStore(running.results).results()
    assert result.entrants["blue_0"] == "readme-bot"
