r"""The closed forms in a notebook: one bounded LaTeX display, for ``_repr_latex_``.

Jupyter shows an object's ``_repr_latex_`` with MathJax (KaTeX in some front ends): the text
must be one display, ``$$ ... $$``, and should stay small. ``display`` writes the equation
and its terms in an ``aligned`` block, in the book's notation (c_{12} = cos(q1 + q2)): a term
whose entries are all short is one matrix, else its entries are written one by one; an entry
too long to read on a screen is left out, and so is everything after the display has grown
to TOTAL_CHARS characters. The entries left out are named at the end, with where to find
them in full (``latex()``, ``save``). The PUMA 560's numeric closed form is some 250,000
characters: in a notebook it shows its short entries and names the others.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy

ENTRY_NODES = 400  # nodes of an entry's expression tree above which it is left out (not even printed)
ENTRY_CHARS = 600  # LaTeX characters of one entry shown at most
MATRIX_CHARS = 2000  # a term whose matrix is at most this long is shown as one matrix
TOTAL_CHARS = 20_000  # the whole display, at most (about)
NAMED = 24  # entries left out that are named one by one; the rest are counted


@dataclass(frozen=True)
class Term:
    """One term of an equation, as shown: its LaTeX label and entry name, and its entries.

    Parameters
    ----------
    label : str
        The term in LaTeX, e.g. ``M(q)``.
    entry : str
        The name of an entry in LaTeX, e.g. ``M`` (written ``M_{12}``) or ``(V_m)``.
    matrix : sympy.Matrix
        The entries, in the notation to show.
    symmetric : bool, optional
        True when the matrix is symmetric: only its upper triangle is written (default False).
    """

    label: str
    entry: str
    matrix: sympy.Matrix
    symmetric: bool = False


def display(equation: str, terms: Sequence[Term], fuller: str) -> str:
    r"""The equation and its terms as one LaTeX display, ``$$\begin{aligned} ... \end{aligned}$$``.

    Parameters
    ----------
    equation : str
        The first row, with its ``&`` (e.g. ``M(q)\,\ddot{q} + ... &= \tau``).
    terms : sequence of Term
        The terms, in the order shown.
    fuller : str
        Plain text saying where the full equations are (e.g. "latex() gives every entry"),
        shown when something is left out.

    Returns
    -------
    str
        The LaTeX text, at most about TOTAL_CHARS characters.
    """
    rows = [equation]
    used = len(equation)
    left_out: list[str] = []
    for term in terms:
        matrix = term.matrix
        height, width = matrix.shape
        places = [(i, j) for i in range(height) for j in range(width) if not (term.symmetric and j < i)]
        texts: dict[tuple[int, int], str | None] = {}
        for place in places:
            texts[place] = _entry(matrix[place]) if used < TOTAL_CHARS else None
        if all(text is not None for text in texts.values()):
            grid = [[texts[min(i, j), max(i, j)] if term.symmetric else texts[i, j] for j in range(width)]
                    for i in range(height)]  # fmt: skip
            whole = _matrix(grid)  # type: ignore[arg-type]
            if len(whole) <= MATRIX_CHARS and used + len(whole) <= TOTAL_CHARS:
                rows.append(f"{term.label} &= {whole}")
                used += len(whole)
                continue
        shown = 0
        for i, j in places:
            name = _entry_name(term.entry, i, j, matrix.shape)
            text = texts[i, j]
            if text is None or used + len(text) > TOTAL_CHARS:
                left_out.append(name)
                continue
            rows.append(f"{name} &= {text}")
            used += len(text)
            shown += 1
        if term.symmetric and shown and height > 1:
            rows.append(rf"{term.entry}_{{ij}} &= {term.entry}_{{ji}} \quad (i > j)")
    if any(_has_short_trig(row) for row in rows):
        rows.append(r"& \text{where } c_{i} = \cos q_{i},\ s_{i} = \sin q_{i},\ c_{ij} = \cos(q_{i} + q_{j}),\ \ldots")
    if left_out:
        named = ", ".join(left_out[:NAMED])
        more = f" \\text{{ and {len(left_out) - NAMED} more}}" if len(left_out) > NAMED else ""
        rows.append(rf"& \text{{Left out here, too long to read: }} {named}{more}")
        rows.append(rf"& \text{{{_text(fuller)}}}")
    return "$$\\begin{aligned}\n" + " \\\\\n".join(rows) + "\n\\end{aligned}$$"


def _small(expr: sympy.Basic) -> bool:
    """True when the expression tree has at most ENTRY_NODES nodes (counted no further than that)."""
    return all(count < ENTRY_NODES for count, _ in enumerate(sympy.preorder_traversal(expr)))


def _entry(expr: sympy.Basic) -> str | None:
    """An entry's LaTeX, or None when it is too long to show."""
    if not _small(expr):
        return None
    text = sympy.latex(expr, full_prec=False)
    return text if len(text) <= ENTRY_CHARS else None


def _entry_name(entry: str, i: int, j: int, shape: tuple[int, int]) -> str:
    """M_{12}; a column's entries G_{1}; with a comma from ten rows on, M_{1,10}."""
    separator = "," if max(shape) >= 10 else ""
    index = f"{i + 1}" if shape[1] == 1 else f"{i + 1}{separator}{j + 1}"
    return f"{entry}_{{{index}}}"


def _matrix(grid: list[list[str]]) -> str:
    rows = " \\\\ ".join(" & ".join(row) for row in grid)
    return f"\\left[\\begin{{matrix}} {rows} \\end{{matrix}}\\right]"


def _has_short_trig(text: str) -> bool:
    return "c_{" in text or "s_{" in text


def _text(text: str) -> str:
    """Plain text for ``\\text{...}``: the characters LaTeX treats specially escaped."""
    special = {"\\": r"\backslash ", "{": r"\{", "}": r"\}", "$": r"\$", "&": r"\&", "#": r"\#", "%": r"\%",
               "_": r"\_", "^": r"\^{}", "~": r"\~{}"}  # fmt: skip
    return "".join(special.get(ch, ch) for ch in text)
