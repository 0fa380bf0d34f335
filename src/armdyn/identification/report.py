"""The validation report of an identified model: how well it predicts held-out torques, how well its
parameters are determined, and whether its links are physically consistent, as Markdown and HTML
with figures (residuals over time and their spectra, predicted against measured torque).

Per joint: the rms and normalized rms of predicted against measured torque (and a reference model's,
such as a published one, on the same samples); per parameter: the estimate, its standard error and
relative standard deviation (Pressé and Gautier, "New criteria of exciting trajectories for robot
identification", ICRA 1993: a relative standard deviation above about 10% marks a poorly identified
parameter); the condition number; per link: the pseudo-inertia's eigenvalues (Wensing, Kim and
Slotine, IEEE RA-L 3(1), 2018) and the triangle inequalities of its principal moments.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from armdyn.identification.workflow import IdentifiedModel, Validation


def comparison(ours: Validation, reference: Validation, label: str = "reference") -> object:
    """Per joint: our rms, the reference's, and the change (%, negative where ours is lower).

    Parameters
    ----------
    ours, reference : Validation
        Predictions of the same samples.
    label : str, optional
        The reference's name in the column headers.

    Returns
    -------
    pandas.DataFrame
        One row per joint.
    """
    import pandas as pd

    return pd.DataFrame(
        {
            "identified rms (N m)": ours.rms,
            f"{label} rms (N m)": reference.rms,
            "change (%)": 100 * (ours.rms - reference.rms) / reference.rms,
        },
        index=pd.Index(ours.joint_names, name="joint"),
    )


def consistency_table(model: IdentifiedModel) -> object:
    """Per link: mass, the pseudo-inertia's eigenvalues and the triangle inequalities.

    Parameters
    ----------
    model : IdentifiedModel
        The identified model (its full parameter vector).

    Returns
    -------
    pandas.DataFrame
        One row per link (``armdyn.identification.consistent.link_consistency``).
    """
    import pandas as pd

    from armdyn.identification.consistent import link_consistency

    n = model.columns.n
    table = link_consistency(model.phi[: 10 * n].reshape(n, 10))
    frame = table if isinstance(table, pd.DataFrame) else pd.DataFrame(table)
    frame.index = pd.Index([link.name for link in model.prior.links][: len(frame)], name="link")
    return frame


def _figures(validation: Validation, directory: Path, stem: str) -> list[str]:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from scipy.signal import welch

    n = validation.measured.shape[1]
    names = []
    fig, axes = plt.subplots(n, 1, figsize=(10, 1.6 * n + 1), sharex=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        ax.plot(validation.t, validation.measured[:, j], lw=0.6, color="0.5", label="measured")
        ax.plot(validation.t, validation.predicted[:, j], lw=0.8, color="C0", label="predicted")
        ax.set_ylabel(f"{validation.joint_names[j]}\n(N m)", fontsize=8)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    fig.suptitle("Predicted against measured torque")
    fig.tight_layout()
    names.append(f"{stem}_torques.png")
    fig.savefig(directory / names[-1], dpi=110)
    plt.close(fig)

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7))
    rate = 1.0 / np.median(np.diff(validation.t))
    for j in range(n):
        top.plot(validation.t, validation.residual[:, j], lw=0.5, label=validation.joint_names[j])
        f, power = welch(validation.residual[:, j], fs=rate, nperseg=min(1024, len(validation.t)))
        bottom.semilogy(f, power, lw=0.8, label=validation.joint_names[j])
    top.set(xlabel="time (s)", ylabel="measured - predicted (N m)", title="Residuals")
    bottom.set(xlabel="frequency (Hz)", ylabel="power (N$^2$ m$^2$/Hz)", title="Residual spectra (Welch)")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=min(n, 7))
    fig.tight_layout()
    names.append(f"{stem}_residuals.png")
    fig.savefig(directory / names[-1], dpi=110)
    plt.close(fig)
    return names


def write_report(
    model: IdentifiedModel,
    directory: str | Path,
    validation: Validation | None = None,
    reference: Validation | None = None,
    reference_label: str = "reference",
) -> Path:
    """Write report.md and report.html (with figures and CSV tables) to a directory.

    Parameters
    ----------
    model : IdentifiedModel
        The identified model.
    directory : str or Path
        Created if absent.
    validation : Validation, optional
        The model's predictions of held-out samples.
    reference : Validation, optional
        A reference model's predictions of the same samples (a published model, the prior).
    reference_label : str, optional
        The reference's name in the tables.

    Returns
    -------
    Path
        The Markdown file.
    """
    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)
    sections: list[tuple[str, str, object]] = []  # (title, text, table)
    prepared = model.prepared
    summary = (
        f"Arm structure: {model.prior.name} ({model.columns.n} joints). Friction law: {model.law.name}. "
        f"Training samples: {len(prepared.q)} after preprocessing (rate {prepared.rate:.6g} Hz, low-pass cut-off "
        f"{prepared.cutoff:.3g} Hz, decimation {prepared.factor}). Condition number of the scaled regressor: "
        f"{model.condition_number:.4g}. Seconds per step: "
        + ", ".join(f"{key} {value:.3g}" for key, value in model.timings.items())
        + "."
    )
    sections.append(("Identification", summary, None))
    figures: list[str] = []
    if validation is not None:
        sections.append(("Held-out samples", f"{len(validation.t)} samples.", validation.table()))
        if reference is not None:
            sections.append(
                (f"Against the {reference_label} model", "", comparison(validation, reference, reference_label))
            )
        figures = _figures(validation, folder, "validation")
    table = model.parameter_table()
    sections.append(("Parameters (least squares on the base parameters)", "", table))
    if model.consistent is not None:
        sections.append(("Physical consistency of each link", "", consistency_table(model)))
    law = model.law
    if law.nonlinear_names:
        import pandas as pd

        frame = pd.DataFrame(law.nonlinear, columns=list(law.nonlinear_names))
        frame.index = pd.Index([f"joint{j + 1}" for j in range(model.columns.n)], name="joint")
        sections.append(("Friction law: nonlinear parameters (variable projection)", "", frame))
    markdown, body = ["# Identification report", ""], ["<h1>Identification report</h1>"]
    for index, (title, text, frame) in enumerate(sections):
        markdown += [f"## {title}", "", text] if text else [f"## {title}", ""]
        body += [f"<h2>{html.escape(title)}</h2>"] + ([f"<p>{html.escape(text)}</p>"] if text else [])
        if frame is not None:
            csv_name = f"table{index}.csv"
            frame.to_csv(folder / csv_name)  # type: ignore[attr-defined]
            markdown += [_markdown_table(frame), ""]
            body.append(frame.to_html(float_format=lambda x: f"{x:.4g}"))  # type: ignore[attr-defined]
    for name in figures:
        markdown += [f"![{name}]({name})", ""]
        body.append(f'<p><img src="{html.escape(name)}" style="max-width:100%"></p>')
    (folder / "report.md").write_text("\n".join(markdown) + "\n")
    page = "<!doctype html><meta charset='utf-8'><title>Identification report</title>" + "\n".join(body)
    (folder / "report.html").write_text(page + "\n")
    return folder / "report.md"


def _cell(value: object) -> str:
    if isinstance(value, (float, np.floating)):
        return f"{value:.4g}"
    return str(value)


def _markdown_table(frame: object) -> str:
    """A pandas DataFrame as a Markdown table (index first)."""
    import pandas as pd

    assert isinstance(frame, pd.DataFrame)
    header = [str(frame.index.name or ""), *map(str, frame.columns)]
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(["---"] * len(header)) + "|"]
    for label, row in frame.iterrows():
        lines.append("| " + " | ".join([str(label), *(_cell(v) for v in row)]) + " |")
    return "\n".join(lines)
