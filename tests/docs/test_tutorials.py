"""The tutorials under docs/tutorials/, run as their reader runs them: every ``sh`` block, in page order, in an empty
folder (``tutorial_runner``), and the files the page has the reader save. Each test ends by checking that it ran
every shell block of its page.

Scale-downs (explicit, and each test fails if the page no longer has the text it replaces):
- training: the page's ``--max-steps 716800`` (8-9 minutes on 2 cores) becomes one batch, ``--max-steps 2048``;
- evaluation: ``--episodes 200`` becomes ``--episodes 4``;
- the league: its 5-minute matches become 1-minute ones (``overrides: {clock_s: 60.0}`` added to the saved YAML).
The match server and the page server listen on free ports instead of the defaults (7447, 8765), so a test never meets
another server: ``--listen``/``--connect``/``--port`` are appended to the commands that take them.
"""
from __future__ import annotations

import json
import re
import time

import msgpack
import pytest
from tutorial_runner import REPO, Shell, Tutorial, filled, scaled, with_args

from ports import free_port

from rocketdrl_ma.results import ResultsStore

TUTORIALS = REPO / "docs" / "tutorials"
TRAIN_STEPS = {"--max-steps 716800": "--max-steps 2048"}
EVAL_EPISODES = {"--episodes 200": "--episodes 4"}
SUCCESS_LINE = re.compile(r"success (\d+\.\d)% over (\d+) episodes, mean return ([+-]?\d+\.\d+)")


@pytest.fixture
def shell(tmp_path):
    s = Shell(tmp_path)
    yield s
    s.stop_all()


def local_endpoint() -> str:
    return f"tcp/127.0.0.1:{free_port()}"


def page_listing(url: str) -> dict:
    """The page server's list message (matches, training runs, replays), as the page asks for it."""
    from websockets.sync.client import connect
    with connect(url.replace("http://", "ws://") + "ws") as ws:
        ws.send(json.dumps({"op": "list"}))
        while True:
            message = msgpack.unpackb(ws.recv(timeout=30), raw=False)
            if message["type"] == "list":
                return message


def wait_until(predicate, timeout_s: float, what: str):
    end = time.monotonic() + timeout_s
    while not (value := predicate()):
        assert time.monotonic() < end, f"timed out after {timeout_s} s waiting for {what}"
        time.sleep(0.2)
    return value


@pytest.mark.slow
@pytest.mark.wall_clock
def test_train_a_penalty_bot_and_watch_it(shell, tmp_path):
    page = Tutorial(TUTORIALS / "train-penalty.md")
    assert "env: minigames/penalty.yaml" in shell.run(page.command("Look at the config"))

    shell.run(scaled(page.command("Train"), TRAIN_STEPS), timeout_s=600)
    run_dir = tmp_path / "runs" / "my_penalty"
    assert (run_dir / "final.pt").is_file() and json.loads((run_dir / "final.json").read_text())

    for title in ("Evaluate your checkpoint", "Evaluate the shipped checkpoint"):
        out = shell.run(scaled(page.command(title), EVAL_EPISODES))
        rate, episodes, _ = SUCCESS_LINE.search(out).groups()
        assert int(episodes) == 4 and 0.0 <= float(rate) <= 100.0 and "outcomes: " in out
        if title == "Evaluate the shipped checkpoint":
            assert float(rate) >= 75.0, out  # the shipped checkpoint scores 100 % over 200 episodes

    endpoint = local_endpoint()
    server = shell.start(with_args(page.command("Terminal 1: the match server"), "--listen", endpoint))
    server.line("serving", 60)
    web = shell.start(with_args(page.command("Terminal 2: the browser page"), "--port", "0", "--connect", endpoint))
    url = web.line("page at ", 60).split()[2]

    create, watch = page.commands("Terminal 3: create the match and record it")
    assert "created match shootout" in shell.run(with_args(create, "--connect", endpoint))
    watcher = shell.start(with_args(watch, "--connect", endpoint))
    watcher.line("watching match shootout", 60)
    wait_until(lambda: "shootout" in {m["id"] for m in page_listing(url)["matches"]}, 30, "the page to list the match")

    out = shell.run(with_args(page.command("Terminal 4: your bot takes the penalties"), "--connect", endpoint))
    assert "match shootout finished" in out, out
    assert watcher.wait(60) == 0, watcher.output()
    assert (tmp_path / "runs" / "shootout.npz").is_file()
    listed = wait_until(lambda: page_listing(url)["replays"], 30, "the page to list the replay")
    assert "runs/shootout.npz" in {r["id"] for r in listed}
    [match] = [m for m in page_listing(url)["matches"] if m["id"] == "shootout"]
    assert match["status"] == "finished"
    web.stop()
    server.stop()

    alone = shell.start(with_args(page.command("The replay without a match server"), "--port", "0"))
    url = alone.line("page at ", 60).split()[2]
    assert "shootout.npz" in {r["id"] for r in page_listing(url)["replays"]}
    page.assert_every_block_run()


#: the packages the remote bot's page has the reader install, and the module each provides; the test does not
#: install from PyPI, it checks that they are what the bot imports and that they import here
BOT_PACKAGES = {"eclipse-zenoh": "zenoh", "msgpack": "msgpack", "cryptography": "cryptography"}


@pytest.mark.wall_clock
def test_a_bot_written_from_the_protocol_page_plays_a_match(shell, tmp_path):
    page = Tutorial(TUTORIALS / "remote-bot.md")
    install = page.command("Install the libraries").split()
    assert install[:2] == ["pip", "install"] and sorted(install[2:]) == sorted(BOT_PACKAGES)
    bot_source = page.write_files(tmp_path)["my_bot.py"].read_text()
    imported = set(re.findall(r"^(?:import|from) (\w+)", bot_source, re.M))
    assert "rocketdrl_ma" not in imported and set(BOT_PACKAGES.values()) <= imported
    for module in BOT_PACKAGES.values():
        __import__(module)

    endpoint = local_endpoint()
    server = shell.start(with_args(page.command("Terminal 1: the match server"), "--listen", endpoint))
    server.line("serving", 60)
    create, watch = page.commands("Terminal 2: create the match and watch it")
    # the longest deadline: lockstep moves on once both actions are in, and this test counts every action on time
    created = shell.run(with_args(create, "--connect", endpoint, "--deadline-ms", "2000"))
    tickets = dict(line.split()[1:3] for line in created.splitlines() if line.startswith("ticket "))
    assert sorted(tickets) == ["blue_0", "orange_0"], created
    watcher = shell.start(with_args(watch, "--connect", endpoint))
    watcher.line("watching match practice", 60)

    opponent = shell.start(with_args(filled(page.command("Terminal 3: the opponent"),
                                            {"<orange_0's ticket>": tickets["orange_0"]}), "--connect", endpoint))
    out = shell.run(with_args(filled(page.command("Terminal 4: your bot"), {"<blue_0's ticket>": tickets["blue_0"]}),
                              "--connect", endpoint), timeout_s=180)
    assert "joined practice as blue_0" in out and re.search(r"match finished: blue \d+ - \d+ orange", out), out
    assert opponent.wait(60) == 0, opponent.output()
    assert watcher.wait(60) == 0, watcher.output()

    out = shell.run(with_args(page.command("Inspect the match"), "--connect", endpoint))
    info = json.loads(out[out.index("{"):])
    blue = info["slot_status"]["blue_0"]
    assert info["status"] == "finished" and blue["bot"] == "my-bot"
    assert blue["received"] >= 0.9 * info["decision"] and info["rejected"] == {}, info
    [result] = ResultsStore(tmp_path / "runs" / "server" / "results.sqlite").results()
    assert result.entrants["blue_0"] == "my-bot"
    page.assert_every_block_run()


#: the league's 5-minute matches become 1-minute ones (12 matches in about a minute on 2 cores)
LEAGUE_CLOCK = {"match: matches/1v1.yaml": "overrides: {clock_s: 60.0}\nmatch: matches/1v1.yaml"}
RATING_LINE = re.compile(r"^\s*(\d+)\. (\S+)\s+mu\s+(-?[\d.]+)\s+sigma\s+([\d.]+)\s+ordinal\s+(-?[\d.]+)"
                         r"\s+W-D-L (\d+)-(\d+)-(\d+)$", re.M)


def ratings(output: str) -> dict[str, tuple[int, int, int, int]]:
    """Rank and W-D-L of each player in the ratings a league prints."""
    return {m[2]: (int(m[1]), int(m[6]), int(m[7]), int(m[8])) for m in RATING_LINE.finditer(output)}


@pytest.mark.slow
def test_run_a_league_of_checkpoints(shell, tmp_path):
    page = Tutorial(TUTORIALS / "league.md")
    config = page.write_files(tmp_path)["my_league.yaml"]
    assert "overrides:" not in config.read_text()
    config.write_text(scaled(config.read_text(), LEAGUE_CLOCK))

    out = shell.run(page.command("Play the league"), timeout_s=300)
    assert "league my_league: 6 scheduled, 0 already stored, 6 played now" in out, out
    first = ratings(out)
    assert set(first) == {"kickstart_6.5M", "first_run_1.09M", "ball_chaser"}
    assert sum(w + d + l for _, w, d, l in first.values()) == 12  # 6 matches, 2 players each

    report = shell.run(page.command("Read the report"))
    for section in ("## Ratings", "## Payoff matrix", "## Team metrics"):
        assert section in report
    assert (tmp_path / "runs" / "league" / "my_league" / "ratings.png").stat().st_size > 0

    with config.open("a") as f:
        f.write(page.text("a fourth entrant for my_league.yaml"))
    out = shell.run(page.command("Play the new entrant's matches"), timeout_s=300)
    assert "league my_league: 12 scheduled, 6 already stored, 6 played now" in out, out
    second = ratings(out)
    assert set(second) == set(first) | {"goalie"}
    assert second["kickstart_6.5M"][0] == 1, out  # the 6.5M self-play policy tops the league (6-0-0 in full matches)
    assert len(ResultsStore(tmp_path / "runs" / "league" / "my_league.sqlite").results()) == 12

    out = shell.run(page.command("Rate the stored matches"))
    assert ratings(out) == second and "played now" not in out
    page.assert_every_block_run()
