"""What a user sees of an arm, a closed form and a property report: print and repr, and the notebook's
HTML and LaTeX (``_repr_html_``, ``_repr_latex_``)."""

from __future__ import annotations

import warnings
from html.parser import HTMLParser

import numpy as np
import pytest

import armdyn as ad
from armdyn import task_space
from armdyn.model.joint import rot_x, trans
from armdyn.properties import COLUMNS
from armdyn.symbolic import derive, motor_symbols, notebook
from tests.helpers import URDFS

RR_TEXT = """\
Robot: two_link_planar, 2 joints (RR), standard DH parameters
Example 3.2-2, two-link planar elbow arm (point masses)
┌────────┬───────┬───┬───┬───────┬────────┬───────┬───────┐
│ joint  │ theta │ d │ a │ alpha │ offset │ q min │ q max │
├────────┼───────┼───┼───┼───────┼────────┼───────┼───────┤
│ theta1 │    q1 │ 0 │ 1 │    0° │     0° │  -inf │   inf │
│ theta2 │    q2 │ 0 │ 1 │    0° │     0° │  -inf │   inf │
└────────┴───────┴───┴───┴───────┴────────┴───────┴───────┘
mass              1, 1 kg
inertia           none (point masses)
gravity           0, -9.8, 0 m/s²
viscous friction  none
Coulomb friction  none
motors            none
configurations    qz = 0°, 0°
                  qh = 90°, 0°"""


def table(text: str) -> tuple[list[str], dict[str, list[str]]]:
    """The boxed table of a printed arm: its headers, and its rows by joint name (the first cell)."""
    lines = [line for line in text.splitlines() if line.startswith("│")]
    cells = [[cell.strip() for cell in line.strip("│").split("│")] for line in lines]
    return cells[0], {row[0]: row for row in cells[1:]}


def cell(text: str, joint: str, column: str) -> str:
    headers, rows = table(text)
    return rows[joint][headers.index(column)]


def fact(text: str, name: str) -> list[str]:
    """The lines of one fact below the table (its name, then the lines continuing it)."""
    lines = text.split("┘\n", 1)[1].splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith(name + "  "))
    found = [lines[start][len(name) :].strip()]
    for line in lines[start + 1 :]:
        if not line.startswith(" "):
            break
        found.append(line.strip())
    return found


@pytest.fixture(scope="module")
def puma() -> ad.Robot:
    return ad.models.puma560()


@pytest.fixture(scope="module")
def panda() -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ad.load_urdf(URDFS["panda"])


# ----- print(arm) and repr(arm) ----------------------------------------------------------------------
def test_print_and_repr_are_the_same_summary(puma: ad.Robot, capsys: pytest.CaptureFixture[str]) -> None:
    print(puma)
    assert capsys.readouterr().out == repr(puma) + "\n"
    assert str(puma) == repr(puma)


def test_the_puma_shows_its_dh_table_and_dynamics(puma: ad.Robot) -> None:
    text = repr(puma)
    assert text.splitlines()[0] == "Robot: puma560, 6 joints (RRRRRR), standard DH parameters"
    assert text.splitlines()[1] == puma.description
    headers, rows = table(text)
    assert headers == ["joint", "theta", "d", "a", "alpha", "offset", "q min", "q max"]
    assert list(rows) == puma.joint_names
    assert [row[1] for row in rows.values()] == ["q1", "q2", "q3", "q4", "q5", "q6"]
    assert cell(text, "q2", "a") == "0.4318"
    assert cell(text, "q3", "a") == "0.0203"
    assert cell(text, "q1", "d") == "0.67183"  # 26.45 inch
    assert cell(text, "q3", "d") == "0.15005"
    assert [row[4] for row in rows.values()] == ["90°", "0°", "-90°", "90°", "-90°", "0°"]
    assert cell(text, "q1", "q min") == "-160°" and cell(text, "q2", "q max") == "225°"
    assert fact(text, "mass") == ["0, 17.4, 4.8, 0.82, 0.34, 0.09 kg"]
    assert fact(text, "inertia") == ["given for every link (about the centre of mass)"]
    assert fact(text, "gravity") == ["0, 0, -9.81 m/s²"]
    assert fact(text, "viscous friction")[0].startswith("G²B = 5.8018, 9.4969,")  # 1.48e-3 * 62.6111^2
    assert fact(text, "Coulomb friction")[0].startswith("|G|Tc+ = 24.731, ")
    assert fact(text, "Coulomb friction")[1].startswith("|G|Tc- = -27.236, ")
    motors = fact(text, "motors")
    assert motors[0].startswith("reflected inertia G²Jm = 0.78403, ")  # 200e-6 * 62.6111^2
    assert motors[1] == "gear ratio G = -62.611, 107.81, -53.706, 76.036, 71.923, 76.686"
    assert fact(text, "configurations") == [
        "qz = 0°, 0°, 0°, 0°, 0°, 0°",
        "qr = 0°, 90°, -90°, 0°, 0°, 0°",
        "qs = 0°, 0°, -90°, 0°, 0°, 0°",
        "qn = 0°, 45°, -180°, 0°, 45°, 0°",
    ]
    assert "tool" not in text and "base " not in text  # both the identity


def test_the_rr_arm_prints_exactly_so() -> None:
    assert repr(ad.models.two_link_planar()) == RR_TEXT


def test_a_prismatic_dh_joint_shows_q_in_d_and_metres() -> None:
    text = repr(ad.models.stanford())
    assert "6 joints (RRPRRR)" in text
    assert table(text)[1]["q3"][1:6] == ["-90°", "q3", "0.0203", "0°", "0"]  # theta, d, a, alpha, offset (m)
    assert cell(text, "q3", "q min") == "0.3048" and cell(text, "q3", "q max") == "1.27"  # 12 and 50 inches
    assert fact(text, "configurations") == ["qz = 0°, 0°, 0.5, 0°, 0°, 0°"]


def test_a_urdf_arm_shows_its_joint_table(panda: ad.Robot) -> None:
    text = repr(panda)
    assert text.splitlines()[0] == "Robot: panda, 9 joints (RRRRRRRPP), a tree"
    headers, rows = table(text)
    assert headers == ["joint", "kind", "parent", "axis", "xyz (m)", "rpy", "q min", "q max"]
    assert list(rows) == panda.joint_names
    assert rows["panda_joint1"][1:6] == ["revolute", "base", "+z", "0, 0, 0.333", "0°, 0°, 0°"]
    assert rows["panda_joint2"][1:6] == ["revolute", "panda_joint1", "+z", "0, 0, 0", "-90°, 0°, 0°"]
    assert rows["panda_joint4"][4] == "0.0825, 0, 0"
    assert rows["panda_finger_joint1"][1:4] == ["prismatic", "panda_joint7", "+y"]
    assert rows["panda_finger_joint2"][1:4] == ["prismatic", "panda_joint7", "-y"]
    assert rows["panda_joint1"][6:] == ["-166°", "166°"]  # 2.8973 rad
    assert rows["panda_finger_joint1"][6:] == ["0", "0.04"]
    assert fact(text, "mass")[0].startswith("4.9707, 0.64693, ")
    assert fact(text, "viscous friction") == [
        "G²B = 0.003, 0.003, 0.003, 0.003, 0.003, 0.003, 0.003, 0.3, 0.3 (at the joints)"
    ]
    assert fact(text, "Coulomb friction") == ["none"] and fact(text, "motors") == ["none"]


def test_a_symbolic_arm_shows_its_symbols_by_name() -> None:
    arm = ad.models.two_link_planar(symbolic=True)
    text = repr(arm)
    assert text.splitlines()[0].endswith("standard DH parameters, symbolic parameters a1, a2, g, m1, m2")
    assert cell(text, "theta1", "a") == "a1" and cell(text, "theta2", "a") == "a2"
    assert cell(text, "theta2", "alpha") == "0°"
    assert fact(text, "mass") == ["m1, m2 kg"]
    assert fact(text, "gravity") == ["0, -g, 0 m/s²"]
    cylinder = repr(ad.models.cylindrical(symbolic=True))
    assert table(cylinder)[1]["r"][1:4] == ["prismatic", "h", "+x"]
    assert fact(cylinder, "mass") == ["0, m1, m2 kg"] and fact(cylinder, "gravity") == ["0, 0, -g m/s²"]


def test_tool_base_and_frame_offsets_are_shown_when_not_the_identity(puma: ad.Robot) -> None:
    moved = puma.replace(tool=trans(z=0.1), base=trans(x=1.0) @ rot_x(np.pi / 2))
    text = repr(moved)
    assert fact(text, "tool") == ["on q6: xyz 0, 0, 0.1 m, rpy 0°, 0°, 0°"]
    assert fact(text, "base") == ["xyz 1, 0, 0 m, rpy 90°, 0°, 0°"]
    reduced = puma.reduced({"q6": 0.0})  # its DH table dropped: a joint table, with the DH frame offsets
    text = repr(reduced)
    assert text.splitlines()[0] == "Robot: puma560, 5 joints (RRRRR), a serial chain"
    headers, rows = table(text)
    assert "offset xyz (m)" in headers and list(rows) == reduced.joint_names
    assert rows["q2"][headers.index("offset xyz (m)")] == "0.4318, 0, 0"
    assert rows["q1"][headers.index("xyz (m)")] == "0, 0, 0.67183"


def test_the_one_line_reprs_that_name_an_arm_stay_one_line(puma: ad.Robot) -> None:
    form = derive(ad.models.two_link_planar(symbolic=True))
    assert repr(form) == "ClosedForm('two_link_planar', n=2, method='recursive')"
    assert "\n" not in ad.properties.check(puma, samples=4, only="gravity").title()


# ----- HTML --------------------------------------------------------------------------------------------
class Tables(HTMLParser):
    """Every table of a page as its rows of cell texts, by class; fails on a tag closed out of order."""

    VOID = frozenset({"br", "hr", "img", "input", "meta", "link"})

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.open: list[str] = []
        self.tables: list[tuple[str, list[list[str]]]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in self.VOID:
            return
        self.open.append(tag)
        if tag == "table":
            self.tables.append((dict(attrs).get("class") or "", []))
        elif tag == "tr":
            self.tables[-1][1].append([])
        elif tag in ("td", "th"):
            self.text = []

    def handle_endtag(self, tag: str) -> None:
        assert self.open and self.open[-1] == tag, f"</{tag}> closes <{self.open[-1] if self.open else None}>"
        self.open.pop()
        if tag in ("td", "th"):
            self.tables[-1][1][-1].append("".join(self.text))

    def handle_data(self, data: str) -> None:
        self.text.append(data)

    @classmethod
    def parse(cls, page: str) -> dict[str, list[list[str]]]:
        parser = cls()
        parser.feed(page)
        parser.close()
        assert not parser.open, f"tags left open: {parser.open}"
        return dict(parser.tables)


@pytest.mark.parametrize("name", ["puma560", "two_link_planar", "panda", "symbolic"])
def test_the_html_holds_the_same_tables(name: str, panda: ad.Robot) -> None:
    arm = {"panda": panda, "symbolic": ad.models.two_link_planar(symbolic=True)}.get(name) or ad.models.load(name)
    tables = Tables.parse(arm._repr_html_())
    assert set(tables) == {"armdyn-joints", "armdyn-dynamics"}
    headers, rows = table(repr(arm))
    joints = tables["armdyn-joints"]
    assert len(joints) == arm.n + 1  # the header row and one per joint
    assert joints[0] == headers
    assert joints[1:] == list(rows.values())
    facts = tables["armdyn-dynamics"]
    assert [row[0] for row in facts][:3] == ["mass", "inertia", "gravity"]
    assert facts[0][1] == fact(repr(arm), "mass")[0]


def test_the_html_escapes_every_text() -> None:
    arm = ad.models.two_link_planar().replace(name="<b>arm</b> & co", description='"quoted" <i>')
    page = arm._repr_html_()
    assert "<b>arm" not in page and "<i>" not in page
    assert "&lt;b&gt;arm&lt;/b&gt; &amp; co" in page and "&quot;quoted&quot; &lt;i&gt;" in page
    Tables.parse(page)


# ----- LaTeX of the closed forms -----------------------------------------------------------------------
@pytest.fixture(scope="module")
def rr_form() -> object:
    return derive(ad.models.two_link_planar(symbolic=True))


def test_the_closed_form_latex_is_one_aligned_display(rr_form: object) -> None:
    text = rr_form._repr_latex_()
    assert text.startswith("$$\\begin{aligned}") and text.endswith("\\end{aligned}$$")
    assert text.count("$$") == 2
    for symbol in ("m_{1}", "m_{2}", "a_{1}", "a_{2}", "c_{2}", "c_{12}", "s_{2}", "\\dot{q}_{1}", "\\cos", "\\sin"):
        assert symbol in text, symbol
    for term in ("M(q) &=", "V_m(q, \\dot{q}) &=", "G(q) &=", "&= \\tau"):
        assert term in text, term
    assert "F(\\dot{q})\n" not in text and "F(\\dot{q}) &=" not in text  # no friction: no F term
    assert "Left out" not in text
    numeric = derive(ad.models.two_link_planar())._repr_latex_()
    assert "9.8 c_{12} + 19.6 c_{1}" in numeric  # G1 = (m1 + m2) g a1 c1 + m2 g a2 c12


def test_a_long_closed_form_is_cut_and_says_what_it_left_out(rr_form: object, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(notebook, "TOTAL_CHARS", 300)
    text = rr_form._repr_latex_()
    assert len(text) < 1500
    assert "Left out here" in text and "latex() gives every entry" in text
    assert "G_{1}" in text.split("Left out here")[1]  # the last term did not fit
    monkeypatch.setattr(notebook, "TOTAL_CHARS", 20_000)
    monkeypatch.setattr(notebook, "ENTRY_NODES", 12)  # M11 is longer than that: entry by entry, M11 left out
    text = rr_form._repr_latex_()
    assert "M_{22} &= a_{2}^{2} m_{2}" in text
    assert "M_{ij} &= M_{ji}" in text
    assert "M_{11}" in text.split("Left out here")[1]


def test_the_task_and_actuated_closed_forms_have_latex_too() -> None:
    task = derive(ad.models.cylindrical(symbolic=True), output=task_space.ToolPosition())._repr_latex_()
    assert task.startswith("$$\\begin{aligned}") and task.endswith("\\end{aligned}$$")
    assert "\\bar{M}(q) &=" in task and "\\bar{N}(q, \\dot{q}) &=" in task and "m_{2}" in task
    actuated = derive(ad.models.two_link_planar(symbolic=True), drives=motor_symbols(2))._repr_latex_()
    assert actuated.startswith("$$\\begin{aligned}") and actuated.endswith("\\end{aligned}$$")
    assert "M'(q) &=" in actuated and "K' &=" in actuated and "J_{M1}" in actuated and "&= K' v" in actuated


# ----- the property report -----------------------------------------------------------------------------
def test_the_report_html_has_one_row_per_property() -> None:
    report = ad.properties.check(ad.models.two_link_planar(), samples=20)
    report.references.update({"m1": 4.0, "m2": 7.0})  # Example 3.3-1
    tables = Tables.parse(report._repr_html_())
    rows = tables["armdyn-properties"]
    assert rows[0] == list(COLUMNS)
    assert len(rows) == len(report.rows) + 1 and len(report.rows) == 13
    assert [row[0] for row in rows[1:]] == [row.name for row in report.rows]
    assert all(row[2] == "yes" for row in rows[1:])
    norm = next(row for row in rows[1:] if row[0] == "norm bounds")
    assert norm[3] == "m1 = 1 kg m^2, m2 = 7 kg m^2" and norm[4] == "m1 = 4 kg m^2, m2 = 7 kg m^2"
    gravity = next(row for row in rows[1:] if row[0] == "gravity bound")
    assert gravity[1] == "||G(q)|| <= gb" and gravity[3].endswith(" N m")
    assert "||G(q)|| &lt;= gb" in report._repr_html_()  # escaped in the page
