"""The documentation cannot drift from the code: every code block of README.md and docs/ runs, and the site
builds with warnings as errors (MkDocs --strict, its pages' code executed by markdown-exec) with an API reference
that covers every public name of armdyn.__all__."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import pytest
from markdown_it import MarkdownIt

import armdyn as ad

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted((ROOT / "docs").rglob("*.md"))
ARMDYN = Path(sys.executable).parent / "armdyn"
QUIET = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "MPLBACKEND": "Agg"}


@dataclass(frozen=True)
class Block:
    """A fenced code block: its language, its options (markdown-exec's key="value" pairs), its code and line."""

    language: str
    options: dict[str, str]
    code: str
    line: int


def blocks(path: Path) -> list[Block]:
    """The fenced code blocks of a Markdown file; an indented code block is refused (it could not say its
    language, so nothing would run it)."""
    found = []
    for token in MarkdownIt("commonmark").parse(path.read_text(encoding="utf-8")):
        line = token.map[0] + 1 if token.map else 0
        if token.type == "code_block":
            raise AssertionError(f"{path.name}:{line}: an indented code block; fence it and name its language")
        if token.type == "fence":
            language, _, rest = token.info.partition(" ")
            options = dict(re.findall(r'(\w+)="([^"]*)"', rest))
            found.append(Block(language.strip(), options, token.content, line))
    return found


def run_python(path: Path, selected: list[Block], shared: bool) -> None:
    """Run the Python blocks in order: in one namespace for the whole file (``shared``), else one per
    markdown-exec session (a block without one runs alone, as markdown-exec runs it)."""
    namespaces: dict[str, dict] = {}
    for index, block in enumerate(selected):
        key = "file" if shared else block.options.get("session", f"alone-{index}")
        namespace = namespaces.setdefault(key, {"__name__": f"{path.stem}_{key}"})
        try:
            exec(compile(block.code, f"{path.name}:{block.line}", "exec"), namespace)
        except Exception as error:
            raise AssertionError(f"{path.name}:{block.line}: the code block fails: {error!r}") from error
        finally:
            plt.close("all")


def run_shell(path: Path, block: Block, folder: Path) -> None:
    """A shell block: each `armdyn ...` line runs (in ``folder``), each `make TARGET` names a Makefile target."""
    targets = set(re.findall(r"^([\w-]+):", (ROOT / "Makefile").read_text(encoding="utf-8"), re.MULTILINE))
    for text in block.code.splitlines():
        words = shlex.split(text.split(" #")[0])
        if not words:
            continue
        where = f"{path.name}:{block.line}: {text.strip()}"
        if words[0] == "make":
            assert all(target in targets for target in words[1:]), f"{where}: no such Makefile target"
        elif words[0] == "armdyn":
            done = subprocess.run([str(ARMDYN), *words[1:]], cwd=folder, env=QUIET, capture_output=True, text=True,
                                  timeout=300)  # fmt: skip
            assert done.returncode == 0, f"{where}: exit {done.returncode}\n{done.stdout}\n{done.stderr}"
        else:
            raise AssertionError(f"{where}: a shell block may hold only `armdyn ...` and `make ...` lines")


def check_markdown(path: Path, folder: Path, shared: bool, executed_by_the_site: bool) -> int:
    """Every block of one file: Python runs (except the blocks markdown-exec runs when the site is built),
    shell lines run or are checked, and any other language is text. Returns the number of blocks checked."""
    found = blocks(path)
    python = [b for b in found if b.language == "python" and not (executed_by_the_site and b.options.get("exec"))]
    run_python(path, python, shared)
    shell = [b for b in found if b.language in ("sh", "bash", "console", "shell")]
    for block in shell:
        run_shell(path, block, folder)
    return len(python) + len(shell)


@pytest.fixture(autouse=True)
def _agg_backend(monkeypatch: pytest.MonkeyPatch) -> None:
    matplotlib.use("Agg")


def test_every_readme_block_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The README's Python blocks run in order in one namespace (from a scratch folder, where they may write),
    its shell lines run; it has no indented code blocks."""
    monkeypatch.chdir(tmp_path)
    assert check_markdown(ROOT / "README.md", tmp_path, shared=True, executed_by_the_site=False) >= 5


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT / "docs")) for p in PAGES])
def test_every_docs_block_runs(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The pages' Python blocks that the site does not execute itself (markdown-exec's exec="on" blocks run in
    the strict build below), and their shell lines."""
    monkeypatch.chdir(ROOT)
    check_markdown(page, tmp_path, shared=False, executed_by_the_site=True)


def test_the_checker_catches_a_broken_block(tmp_path: Path) -> None:
    """A block that raises, a shell line that fails, an unknown Makefile target and an indented code block each
    make the check fail, naming the file and line."""
    cases = {
        "raises.md": "# t\n\n```python\nx = 1\n```\n\n```python\nx / 0\n```\n",
        "shell.md": "```sh\narmdyn no-such-command\n```\n",
        "make.md": "```sh\nmake no-such-target\n```\n",
        "indented.md": "Text.\n\n    x = 1\n",
    }
    for name, text in cases.items():
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        with pytest.raises(AssertionError, match=re.escape(name)):
            check_markdown(path, tmp_path, shared=True, executed_by_the_site=False)
    good = tmp_path / "good.md"
    good.write_text("```python\nx = 2\n```\n\n```python\nassert x == 2\n```\n\n```text\nnot run\n```\n")
    assert check_markdown(good, tmp_path, shared=True, executed_by_the_site=False) == 2


def _build(config: Path, site: Path) -> subprocess.CompletedProcess:
    command = [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config), "-d", str(site)]
    return subprocess.run(command, cwd=ROOT, env=QUIET, capture_output=True, text=True, timeout=900)


@pytest.fixture(scope="module")
def built_site(tmp_path_factory: pytest.TempPathFactory) -> tuple[subprocess.CompletedProcess, Path]:
    """The site built once, as `make docs` builds it: the build's outcome and its folder."""
    site = tmp_path_factory.mktemp("docs") / "site"
    return _build(ROOT / "mkdocs.yml", site), site


def test_the_site_builds_strict_with_the_whole_api(built_site: tuple[subprocess.CompletedProcess, Path]) -> None:
    """`mkdocs build --strict` (what `make docs` runs): no warning, every executed block of every page ran, and
    the API reference has an entry for every name of armdyn.__all__."""
    done, site = built_site
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-8000:]
    reference = "".join(path.read_text(encoding="utf-8") for path in (site / "reference").rglob("*.html"))
    missing = [name for name in ad.__all__ if f'id="armdyn.{name}"' not in reference]
    assert not missing, f"the API reference lacks {missing}"
    for page in PAGES:
        html = site / page.relative_to(ROOT / "docs").with_suffix(".html")
        assert html.is_file(), f"{page.name} was not built"
        assert "Traceback" not in html.read_text(encoding="utf-8"), f"{page.name} shows a traceback"


HREF = re.compile(r'<(?:a|link|script|img|source)\b[^>]*?\b(?:href|src)="([^"]*)"')
ARITHMATEX = re.compile(r'class="arithmatex"|\$\$')


def test_every_link_of_the_site_works_from_file_urls(built_site: tuple[subprocess.CompletedProcess, Path]) -> None:
    """The site reads from file:// without a server or a network: every relative href and src of every page names
    an existing file (a folder would open as a listing), no page loads a script or a stylesheet from the network,
    and the offline search has its inlined index and the Web Worker shim beside it."""
    done, site = built_site
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-8000:]
    # 404.html is what a web server answers for a missing address (its links are absolute); file:// never opens it
    pages = sorted(path for path in site.rglob("*.html") if path.name != "404.html")
    assert len(pages) >= len(PAGES), "the site has fewer pages than docs/"
    broken = []
    for page in pages:
        text = page.read_text(encoding="utf-8")
        for link in HREF.findall(text):
            if link.startswith(("#", "mailto:", "data:", "javascript:")):
                continue
            if link.startswith(("http://", "https://", "//")):
                tag = text[: text.index(link)].rsplit("<", 1)[-1]
                if tag.startswith(("script", "link")):
                    broken.append(f"{page.relative_to(site)}: loads {link} from the network")
                continue
            target = (page.parent / link.split("#")[0].split("?")[0]).resolve()
            if not target.is_file():
                broken.append(f"{page.relative_to(site)}: {link} -> {'a folder' if target.is_dir() else 'nothing'}")
    assert not broken, "\n".join(broken[:40])
    assert (site / "search" / "search_index.js").is_file()
    assert (site / "assets" / "javascripts" / "iframe-worker.js").is_file()


def test_the_equations_are_typeset_as_mathml(built_site: tuple[subprocess.CompletedProcess, Path]) -> None:
    """Every equation of the pages is MathML in the built site (no script typesets it when the page opens): the
    robot equation on the home page, the task-space equation with its barred terms, and no formula left as TeX."""
    done, site = built_site
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-8000:]
    for page in PAGES:
        source = page.read_text(encoding="utf-8")
        html = (site / page.relative_to(ROOT / "docs").with_suffix(".html")).read_text(encoding="utf-8")
        displayed = len(re.findall(r"^\$\$$", source, re.MULTILINE)) // 2
        assert html.count('<div class="math-display"><math') == displayed, f"{page.name}: an equation is not MathML"
        assert not ARITHMATEX.search(html), f"{page.name}: a formula is left as TeX"
    assert "<msub><mi>V</mi><mi>m</mi></msub>" in (site / "index.html").read_text(encoding="utf-8")
    task = (site / "task-space.html").read_text(encoding="utf-8")
    assert task.count("&#x000AF;") >= 10, "the task-space page lacks its barred terms (Mbar, Nbar, ...)"


def test_a_broken_page_fails_the_strict_build(tmp_path: Path) -> None:
    """markdown-exec reports a failing block as a warning, which --strict turns into a failed build."""
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "index.md").write_text('# t\n\n```python exec="on"\nraise ValueError("broken")\n```\n', encoding="utf-8")
    config = tmp_path / "mkdocs.yml"
    settings = f"site_name: t\ndocs_dir: {docs}\nplugins: [markdown-exec]\nmarkdown_extensions: [pymdownx.superfences]"
    config.write_text(settings, encoding="utf-8")
    done = _build(config, tmp_path / "site")
    assert done.returncode != 0
    assert "broken" in done.stdout + done.stderr
