"""Learning curves: success rate and return against agent steps, read back from a run's TensorBoard logs."""
from __future__ import annotations

from pathlib import Path


def read_scalars(run_dir: str | Path, tag: str, required: bool = True) -> list[tuple[int, float]]:
    """Every (step, value) of ``tag`` in the run's event files (resumed runs append to the same folder)."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    points: dict[int, float] = {}
    for events in sorted(Path(run_dir).glob("events.out.tfevents.*")):
        acc = EventAccumulator(str(events), size_guidance={"scalars": 0})
        acc.Reload()
        if tag in acc.Tags()["scalars"]:
            points.update({e.step: e.value for e in acc.Scalars(tag)})
    if not points and required:
        raise ValueError(f"run_dir: no {tag!r} scalars under {run_dir}")
    return sorted(points.items())


def plot_curves(runs: dict[str, str | Path], out: str | Path, title: str = "") -> Path:
    """One PNG with two panels (success rate, mean return) and one line per labelled run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_s, ax_r) = plt.subplots(1, 2, figsize=(11, 4))
    for label, run_dir in runs.items():
        for ax, tag in ((ax_s, "episode/success_rate"), (ax_r, "episode/return")):
            steps, values = zip(*read_scalars(run_dir, tag))
            line, = ax.plot([s / 1e6 for s in steps], [100 * v if ax is ax_s else v for v in values], label=label)
        levels = read_scalars(run_dir, "curriculum/difficulty", required=False)
        if levels:  # the curriculum's difficulty, a step line on the success panel
            ax_s.step([s / 1e6 for s, _ in levels] + [steps[-1] / 1e6], [100 * v for _, v in levels] +
                      [100 * levels[-1][1]], where="post", linestyle="--", color=line.get_color(), alpha=0.6,
                      label=f"{label}: curriculum difficulty (%)")
    ax_s.set(xlabel="agent steps (millions)", ylabel="success rate (%) of training episodes", ylim=(0, 100))
    ax_r.set(xlabel="agent steps (millions)", ylabel="mean env return per episode")
    for ax in (ax_s, ax_r):
        ax.grid(alpha=0.3)
        ax.legend()
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
