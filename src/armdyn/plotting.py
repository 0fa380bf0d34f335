"""Figures of simulated runs, laid out as the book's Chapter 4 figures."""

from __future__ import annotations

from pathlib import Path


def plot_result(result: object, path: str | Path | None = None, title: str | None = None) -> object:
    """Joint values (solid) with their desired values (dashed), tracking errors, and torques."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = result.q.shape[1]
    rows = 3 if result.q_d is not None else 2
    fig, axes = plt.subplots(rows, 1, figsize=(8, 2.6 * rows), sharex=True, constrained_layout=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    names = result.arm.joint_names
    for i in range(n):
        colour = colours[i % len(colours)]
        axes[0].plot(result.t, result.q[:, i], color=colour, label=f"{names[i]}")
        if result.q_d is not None:
            axes[0].plot(result.t, result.q_d[:, i], color=colour, linestyle="--", label=f"{names[i]} desired")
            axes[1].plot(result.t, result.error[:, i], color=colour, label=f"e{i + 1}")
        axes[-1].plot(result.t, result.tau[:, i], color=colour, label=f"tau{i + 1}")
    axes[0].set_ylabel("joint value (rad or m)")
    axes[0].set_title(title or f"{result.arm.name}: simulated response")
    if result.q_d is not None:
        axes[1].set_ylabel("tracking error e = q_d - q")
        axes[1].axhline(0.0, color="0.6", linewidth=0.8)
    axes[-1].set_ylabel("torque (N m or N)")
    axes[-1].set_xlabel("time (s)")
    for axis in axes:
        axis.grid(True, alpha=0.3)
        axis.legend(loc="upper right", fontsize=8, ncol=min(n, 3))
    axes[-1].set_xlim(result.t[0], result.t[-1])
    if path is not None:
        fig.savefig(path, dpi=150)
        plt.close(fig)
    return fig
