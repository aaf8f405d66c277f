"""The league page in a real headless Chromium: a tiny league of scripted bots is played into a results store, and
`rocketdrl-ma web --league` shows its standings, ratings with their intervals and payoff matrix as the league's own
rating code computes them; a match's replay link plays it again from its seed and opens it in the viewer, ending on
the stored score."""
from __future__ import annotations

import pytest
import yaml

from web_helpers import Procs, launch_chromium

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("test_page")]
VIEWPORT = {"width": 1280, "height": 720}
ENTRANTS = ["ball_chaser", "goalie", "idle"]


@pytest.fixture(scope="module")
def league(tmp_path_factory):
    """A played league: its config, stored results and the ratings the league code gives them."""
    from rocketdrl_ma.league.config import load_league_config
    from rocketdrl_ma.league.ratings import rate
    from rocketdrl_ma.league.runner import run_league
    from rocketdrl_ma.league.schedule import schedule
    from rocketdrl_ma.results import ResultsStore

    tmp = tmp_path_factory.mktemp("league")
    config = {"name": "tiny", "match": "matches/1v1.yaml", "format": "per_pair", "matches_per_pair": 1, "seed": 3,
              "overrides": {"clock_s": 6.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
              "results": str(tmp / "results.sqlite"), "report": str(tmp / "report"),
              "entrants": [{"name": name, "policy": f"scripted:{name}"} for name in ENTRANTS]}
    path = tmp / "tiny.yaml"
    path.write_text(yaml.safe_dump(config))
    cfg = load_league_config(path)
    run = run_league(cfg, at_once=3)
    assert run.played == 3
    with ResultsStore(cfg.results) as store:
        results = store.results()
    return {"path": path, "cfg": cfg, "results": results, "table": rate(cfg, schedule(cfg), results)}


@pytest.fixture(scope="module")
def page(league):
    from playwright.sync_api import sync_playwright

    procs = Procs()
    try:
        _, url = procs.web("--no-zenoh", "--replays", str(league["path"].parent / "none"), "--league",
                           str(league["path"]))
        with sync_playwright() as playwright:
            browser = launch_chromium(playwright)
            page = browser.new_page(viewport=VIEWPORT)
            errors: list[str] = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url + "league")
            page.wait_for_selector("#matches tr:nth-child(2)", timeout=30_000)
            yield page
            browser.close()
            assert errors == []
    finally:
        procs.stop_all()


def rows(page, table: str) -> list[list[str]]:
    return page.evaluate(f"""[...document.querySelectorAll('#{table} tr')].slice(1)
        .map((tr) => [...tr.children].map((td) => td.textContent))""")


def test_standings_ratings_and_payoff_are_the_leagues(page, league):
    table, results = league["table"], league["results"]
    assert page.inner_text("#league-title") == "League tiny"
    assert "3 of 3 scheduled matches" in page.inner_text("#league-about")
    standings = {row[1]: row for row in rows(page, "standings")}
    assert set(standings) == set(ENTRANTS)
    for name in ENTRANTS:
        wins = sum(1 for r in results if r.winner is not None
                   and {"blue": r.entrants["blue_0"], "orange": r.entrants["orange_0"]}[r.winner] == name)
        assert int(standings[name][3]) == wins
        assert int(standings[name][2]) == 2  # each entrant meets the two others once
    ratings = rows(page, "ratings")
    assert [r[1] for r in ratings] == [r.name for r in table.ratings]  # ranked by ordinal, as the report
    for shown, rating in zip(ratings, table.ratings):
        assert float(shown[2]) == pytest.approx(rating.mu, abs=0.005)
        assert float(shown[3]) == pytest.approx(rating.sigma, abs=0.005)
        assert float(shown[4]) == pytest.approx(rating.mu - 3 * rating.sigma, abs=0.005)
    assert page.locator("#ratings .interval .range").count() == len(ENTRANTS)
    payoff = rows(page, "payoff")
    names = [e.name for e in league["cfg"].entrants]
    for row in payoff:
        a = row[0]
        for b, shown in zip(names, row[1:]):
            expected = "–" if a == b else f"{table.payoff[a][b]:.2f} ({table.games[a][b]})"
            assert shown == expected, (a, b)


def test_a_matchs_replay_is_played_again_and_ends_on_the_stored_score(page, league):
    first = rows(page, "matches")[0]
    stored = next(r for r in league["results"] if r.match_key == first[0])
    with page.expect_navigation():
        page.click("#matches tr:nth-child(2) a")
    page.wait_for_function("window.__view && window.__view.mode() === 'league' && window.__view.roster() !== null",
                           timeout=120_000)
    assert "played again from its seed" in page.inner_text("#title")
    assert page.inner_text("#notice") == "" or page.is_hidden("#notice")
    page.click("#play")  # pause, then the last state
    page.eval_on_selector("#seek", "(el) => { el.value = el.max; el.dispatchEvent(new Event('input')); }")
    page.wait_for_function("window.__view.tick() === Number(document.getElementById('seek').max)")
    assert page.evaluate("window.__view.score()") == [stored.score_blue, stored.score_orange]
    page.go_back()
    page.wait_for_selector("#matches tr:nth-child(2)", timeout=30_000)
