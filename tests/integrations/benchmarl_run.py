"""Short BenchMARL experiments on this env, run by test_benchmarl.py in the BenchMARL venv (one process for all, so
torch, BenchMARL and the physics load once): ``python benchmarl_run.py OUT_DIR RUNS_JSON``, RUNS_JSON a list of
``{"algorithm": "mappo" | "ippo", "task": <RocketDRLTask member>, "config": <task config dict>, "render": bool}``.
Prints one JSON line per run with what the test checks."""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from benchmarl.algorithms import IppoConfig, MappoConfig
from benchmarl.experiment import Callback, Experiment, ExperimentConfig
from benchmarl.models.mlp import MlpConfig

from rocketdrl_ma.integrations.benchmarl import RocketDRLTask

ALGORITHMS = {"mappo": MappoConfig, "ippo": IppoConfig}


class LossRecorder(Callback):
    """Every loss value of every optimiser step, per group."""

    def __init__(self):
        super().__init__()
        self.losses: dict[str, list[float]] = {}

    def on_train_end(self, training_td, group):
        values = self.losses.setdefault(group, [])
        for key, value in training_td.items():
            if key.startswith("loss_"):
                values.extend(float(v) for v in value.flatten())


def run(algorithm: str, task_name: str, task_config: dict, render: bool, out_dir: str) -> dict:
    """Two iterations of 64 frames on two games, an evaluation episode after each, a checkpoint at the end, CSV
    logs; ``render``: BenchMARL's default, evaluation videos when its logger can write them."""
    task = getattr(RocketDRLTask, task_name).get_task(task_config)
    config = ExperimentConfig.get_from_yaml()
    config.max_n_iters = 2
    config.on_policy_collected_frames_per_batch = 64
    config.on_policy_n_envs_per_worker = 2
    config.on_policy_n_minibatch_iters = 2
    config.on_policy_minibatch_size = 32
    config.evaluation = True
    config.evaluation_interval = 64
    config.evaluation_episodes = 1
    config.render = render
    config.loggers = ["csv"]
    config.create_json = True
    config.save_folder = out_dir
    config.checkpoint_at_end = True
    model = MlpConfig.get_from_yaml()
    model.num_cells = [32, 32]
    recorder = LossRecorder()
    experiment = Experiment(task=task, algorithm_config=ALGORITHMS[algorithm].get_from_yaml(), model_config=model,
                            seed=0, config=config, callbacks=[recorder])
    experiment.run()
    return {
        "group_map": experiment.group_map,
        "state_spec": list(experiment.state_spec.keys()) if experiment.state_spec is not None else None,
        "iterations": experiment.n_iters_performed,
        "frames": experiment.total_frames,
        "losses": {g: [v if math.isfinite(v) else str(v) for v in vs] for g, vs in recorder.losses.items()},
        "folder": str(experiment.folder_name),
        "files": sorted(str(p.relative_to(experiment.folder_name)) for p in Path(experiment.folder_name).rglob("*")
                        if p.is_file()),
    }


if __name__ == "__main__":
    out_dir, runs = sys.argv[1], json.loads(sys.argv[2])
    for spec in runs:
        print(json.dumps(run(spec["algorithm"], spec["task"], spec["config"], spec["render"], out_dir)), flush=True)
