"""``rocketdrl-ma train CONFIG``, ``eval CHECKPOINT --episodes N``, ``curves RUN_DIR...`` and ``duel CONFIG CONFIG``
(standard library at the top, so ``--help`` stays fast)."""
from __future__ import annotations

import argparse
from pathlib import Path


def _run_train(args: argparse.Namespace) -> int:
    from rocketdrl_ma.policies.ppo import load_train_config, train
    from rocketdrl_ma.policies.ppo.trainer import worker_plan

    overrides = {} if args.max_steps is None else {"max_steps": args.max_steps}
    if args.seed is not None:
        overrides["seed"] = args.seed
    if args.asynchronous:
        overrides["async"] = True
    cfg = load_train_config(args.config, overrides)
    plan = worker_plan(cfg, args.workers, args.ray)
    name = Path(args.config).stem
    run_dir = Path(args.run_dir or Path("runs") / name)
    out = Path(args.out or run_dir / "final.pt")
    curve = _start_rating_curve(args.rating_curve, run_dir, out) if args.rating_curve else None
    watch = None
    if cfg.watch_every:  # evaluation episodes for `rocketdrl-ma web`, published on Zenoh
        from rocketdrl_ma.web.training import broadcast_from_train_config
        watch = broadcast_from_train_config(cfg, run_dir)
    result = train(cfg, out=out, run_dir=run_dir, resume=args.resume, progress=not args.quiet, watch=watch,
                   workers=plan)
    for steps, success, ret, episodes in result.history:
        print(f"steps {steps:>10,d}  success {success:6.1%}  return {ret:+8.2f}  episodes {episodes}")
    print(f"checkpoint: {result.checkpoint} ({result.agent_steps:,d} agent steps); TensorBoard logs: {run_dir}")
    if curve is not None:
        print(f"rating curve: rating the final checkpoint in the background (pid {curve.pid}); it writes "
              f"{run_dir / 'rating_curve'} and logs to {run_dir / 'rating_curve.log'}")
    return 0


def _start_rating_curve(config: str, run_dir: Path, final: Path):
    """``league-curve CONFIG --follow`` on this run in its own process (a background league): it rates each snapshot
    as it is written and the final checkpoint, and stops if this training dies first."""
    import os
    import subprocess
    import sys

    from rocketdrl_ma.league.curve_config import load_curve_config

    load_curve_config(config)  # a bad curve config fails now, not after the training
    run_dir.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "rocketdrl_ma.cli", "league-curve", config, "--run-dir", str(run_dir),
               "--final", str(final), "--follow", "--follow-pid", str(os.getpid()), "--poll-s", "30"]
    with open(run_dir / "rating_curve.log", "a") as log:
        # its own session: a Ctrl-C of the training stops the training, and the curve rates what it left
        return subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


def _run_eval(args: argparse.Namespace) -> int:
    from rocketdrl_ma.policies.ppo import evaluate, evaluate_against, evaluate_policy

    scripted = args.checkpoint.startswith("scripted:")
    if scripted != (args.env is not None):
        raise ValueError("--env: the env config a scripted bot plays (e.g. eval scripted:aerial_shooter --env "
                         "minigames/aerial.yaml); a checkpoint plays the env it trained on, so only with a bot")
    if scripted:
        r = evaluate_policy(args.checkpoint, args.env, args.episodes, seed=args.seed, n_envs=args.n_envs,
                            opponent=args.opponent, side=args.side or "blue")
    elif args.opponent is None:
        if args.side is not None:
            raise ValueError("--side: only with --opponent (alone, the checkpoint plays every car)")
        r = evaluate(args.checkpoint, args.episodes, seed=args.seed, n_envs=args.n_envs)
    else:
        r = evaluate_against(args.checkpoint, args.opponent, args.episodes, seed=args.seed, n_envs=args.n_envs,
                             side=args.side)
    against = "" if args.opponent is None else f" against {args.opponent}"
    print(f"{args.checkpoint}{against}: success {r.success_rate:.1%} over {r.episodes} episodes, "
          f"mean return {r.mean_return:+.2f}, mean length {r.mean_length:.1f} decisions")
    print(f"outcomes: {r.outcomes_text()}")
    return 0


def _run_curves(args: argparse.Namespace) -> int:
    from rocketdrl_ma.policies.ppo.curves import plot_curves

    runs = {}
    for item in args.runs:
        label, sep, path = item.partition("=")
        runs[label if sep else Path(item).name] = path if sep else item
    print(plot_curves(runs, args.out, args.title))
    return 0


def _run_duel(args: argparse.Namespace) -> int:
    from rocketdrl_ma.policies.duel import duel
    from rocketdrl_ma.policies.ppo import load_train_config
    from rocketdrl_ma.policies.ppo.trainer import worker_plan

    learners = {Path(path).stem: load_train_config(path) for path in args.configs}
    if len(learners) != len(args.configs):
        raise ValueError(f"configs: two learners need two differently named YAMLs, got {args.configs}")
    plan = worker_plan(next(iter(learners.values())), args.workers)
    for phase in duel(learners, args.root, args.cycles, args.phase_steps, plan, progress=not args.quiet):
        stopped = "  (stopped: the duel ends here; run the command again to go on)" if phase.stopped else ""
        print(f"cycle {phase.cycle}  {phase.learner:<24} {phase.agent_steps:>10,d} agent steps  {phase.checkpoint}"
              f"{stopped}")
    return 0


def add_commands(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("train", help="train a PPO policy (torchrl) from a training YAML, e.g. policies/penalty.yaml")
    p.add_argument("config", help="training YAML: ML-Agents PPO keys plus env, env_overrides, n_envs, seed")
    p.add_argument("--out", default=None, help="final checkpoint path (default RUN_DIR/final.pt)")
    p.add_argument("--run-dir", default=None, help="TensorBoard logs and periodic checkpoints (default runs/NAME)")
    p.add_argument("--resume", default=None, help="continue from this checkpoint (its step count and optimizer)")
    p.add_argument("--max-steps", type=int, default=None, help="override max_steps (agent steps)")
    p.add_argument("--seed", type=int, default=None, help="override the config's seed")
    p.add_argument("--workers", type=int, default=None,
                   help="rollout worker processes (default: the config's n_workers, else one per CPU core; "
                        "0: step the env copies in this process)")
    p.add_argument("--ray", default=None, metavar="auto|HOST:PORT",
                   help="run the rollout workers on a Ray cluster (`pip install rocketdrl-ma[cluster]`): 'auto' "
                        "joins the cluster this machine belongs to, HOST:PORT a head node's address")
    p.add_argument("--async", dest="asynchronous", action="store_true",
                   help="update on each worker's batch as it arrives (overlaps collection and learning)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--rating-curve", default=None, metavar="CURVE_YAML",
                   help="rate every snapshot against pinned anchors while training, in a background process "
                        "(`league-curve`), e.g. leagues/curves/curve_2v2.yaml; the curve goes to RUN_DIR/rating_curve")
    p.set_defaults(run=_run_train)
    e = sub.add_parser("eval", help="greedy evaluation of a checkpoint (or a scripted bot): success rate and mean "
                                    "return")
    e.add_argument("checkpoint", help="a .pt checkpoint with its .json next to it, or scripted:BOT with --env")
    e.add_argument("--env", default=None, metavar="CONFIG",
                   help="with scripted:BOT: the env config it plays (a checkpoint plays the one it trained on)")
    e.add_argument("--episodes", type=int, default=200)
    e.add_argument("--n-envs", type=int, default=4, help="env copies played side by side")
    e.add_argument("--seed", type=int, default=10_000, help="first env seed (training uses 0..n_envs-1)")
    e.add_argument("--opponent", default=None, metavar="SPEC",
                   help="a policy (scripted:goalie, checkpoint:PATH) for the other team's cars; success is then the "
                        "checkpoint's team winning (e.g. the penalty duel keeper's save)")
    e.add_argument("--side", default=None, choices=("blue", "orange"),
                   help="with --opponent: the checkpoint's team (default: the side it trained on, else blue)")
    e.set_defaults(run=_run_eval)
    c = sub.add_parser("curves", help="plot success rate and return vs agent steps from training runs' logs")
    c.add_argument("runs", nargs="+", help="run directories (runs/NAME), optionally LABEL=DIR")
    c.add_argument("--out", required=True, help="PNG to write")
    c.add_argument("--title", default="")
    c.set_defaults(run=_run_curves)
    d = sub.add_parser("duel", help="train two self-play learners in turn against each other's snapshots "
                                    "(the penalty duel's shooter and keeper)")
    d.add_argument("configs", nargs="+", help="one training YAML per learner, each with selfplay.side; the first "
                                              "trains first")
    d.add_argument("--cycles", type=int, default=6)
    d.add_argument("--phase-steps", type=int, default=500_000, help="agent steps of each learner per phase")
    d.add_argument("--root", default="runs/penalty_duel", help="learner NAME runs in ROOT/NAME (resumed if there)")
    d.add_argument("--workers", type=int, default=None, help="rollout worker processes (as for train)")
    d.add_argument("--quiet", action="store_true", help="no progress bar")
    d.set_defaults(run=_run_duel)
