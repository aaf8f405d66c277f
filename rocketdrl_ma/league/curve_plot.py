"""A rating curve drawn (``curve.png``) and written for TensorBoard, beside the run's own training curves."""
from __future__ import annotations

from pathlib import Path

from .curve import CurvePoint
from .curve_config import CurveConfig


def plot_curve(cfg: CurveConfig, points: list[CurvePoint], out: Path, title: str) -> Path:
    """Rating against agent steps with its 95 % interval, the pinned anchors as dashed lines, and training hours
    along the top where the snapshots record them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    steps_m = [p.agent_steps / 1e6 for p in points]
    ax.fill_between(steps_m, [p.low for p in points], [p.high for p in points], alpha=0.25, label="95 % interval")
    ax.plot(steps_m, [p.mu for p in points], marker="o", label="rating (mu)")
    for anchor in cfg.anchors:
        ax.axhline(anchor.mu, linestyle="--", linewidth=0.8, color="grey")
        ax.annotate(anchor.name, (1.0, anchor.mu), xycoords=("axes fraction", "data"), fontsize=8,
                    ha="right", va="bottom", color="dimgrey")
    ax.set_xlabel("agent steps (millions)")
    ax.set_ylabel("openskill rating")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize=8)
    hours = [(s, p.train_hours) for s, p in zip(steps_m, points) if p.train_hours is not None]
    if len(hours) >= 2:
        top = ax.secondary_xaxis("top", functions=(_interp(hours, 0, 1), _interp(hours, 1, 0)))
        top.set_xlabel("training hours")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    plt.close(fig)
    return out


def _interp(pairs: list[tuple[float, float]], src: int, dst: int):
    import numpy as np

    xs, ys = np.array([p[src] for p in pairs]), np.array([p[dst] for p in pairs])
    return lambda x: np.interp(x, xs, ys)


def write_tensorboard(points: list[CurvePoint], log_dir: Path) -> Path:
    """``rating/mu``, ``rating/ci_low``, ``rating/ci_high`` and ``rating/points_vs_<anchor>`` at each snapshot's
    agent steps; the folder's earlier event files are replaced, so a curve re-rated is written once."""
    from torch.utils.tensorboard import SummaryWriter

    log_dir.mkdir(parents=True, exist_ok=True)
    for old in log_dir.glob("events.out.tfevents.*"):
        old.unlink()
    with SummaryWriter(log_dir=str(log_dir)) as writer:
        for p in points:
            writer.add_scalar("rating/mu", p.mu, p.agent_steps)
            writer.add_scalar("rating/ci_low", p.low, p.agent_steps)
            writer.add_scalar("rating/ci_high", p.high, p.agent_steps)
            for anchor, share in p.points.items():
                writer.add_scalar(f"rating/points_vs_{anchor}", share, p.agent_steps)
    return log_dir
