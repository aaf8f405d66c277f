"""Leagues: a deterministic schedule of matches between entrants of any kind (checkpoints, scripted
bots, remote bots on the match server), results appended to the shared SQLite store, openskill
ratings, a win-rate payoff matrix and a markdown + PNG report.

``config.py`` validates league YAMLs, ``schedule.py`` lists the matches and their keys, ``play.py``
plays one (locally or on the server), ``remote.py`` invites remote bots, ``runner.py`` plays what the
store lacks, ``ratings.py`` rates, ``report.py`` writes the report, ``commands.py`` is the CLI.
"""
