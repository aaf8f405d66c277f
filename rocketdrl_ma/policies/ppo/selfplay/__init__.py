"""Self-play: one PPO policy plays both teams (team-relative observations) against an opponent pool of
its own past snapshots and scripted bots, picked by prioritised fictitious self-play.

``config.py`` types the training YAML's ``selfplay:`` section and its teachers (``imitate``, ``kickstart``),
``pfsp.py`` weighs opponents, ``games.py`` is what a rollout worker steps (rows are the learner's cars only;
scripted opponents and the kickstart teacher act there), ``pool.py`` the learner's side (the opponent table,
PFSP's results, snapshots in slots whose weights travel to the workers with the learner's), ``imitation.py`` the
warm start, ``kickstart.py`` the fading distillation term.
"""
