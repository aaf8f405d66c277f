"""Self-play: one PPO policy plays both teams (team-relative observations) against an opponent pool of
its own past snapshots and scripted bots, picked by prioritised fictitious self-play.

``config.py`` checks the training YAML's ``selfplay:`` section, ``pfsp.py`` weighs opponents,
``pool.py`` is the env pool the PPO trainer (``policies/ppo/trainer.py``) drives instead of its own
when that section is set: rows are the learner's cars only, the opponents act inside the pool.
"""
