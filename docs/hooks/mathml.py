"""Typeset the pages' mathematics when the site is built.

pymdownx.arithmatex (generic mode) marks each formula of a page, ``$...$`` inline and ``$$...$$`` displayed; this
MkDocs hook turns each into MathML with latex2mathml. Browsers render MathML natively (MathML Core), so a page needs
no script and no network to show its equations: the site reads the same from a server and from file://. A formula
latex2mathml cannot read stops the build, naming the page and the formula.
"""

from __future__ import annotations

import html
import re
from typing import Any

from latex2mathml.converter import convert
from mkdocs.exceptions import PluginError

# arithmatex's generic output: the TeX, HTML-escaped, between \( \) in a span or \[ \] in a div
INLINE = re.compile(r'<span class="arithmatex">\\\((.*?)\\\)</span>', re.DOTALL)
DISPLAY = re.compile(r'<div class="arithmatex">\\\[(.*?)\\\]</div>', re.DOTALL)


def mathml(tex: str, display: str, where: str) -> str:
    """The MathML of one formula, ``display`` "inline" or "block"."""
    source = html.unescape(tex).strip()
    try:
        markup = convert(source, display=display)
    except Exception as error:
        raise PluginError(f"{where}: latex2mathml cannot typeset {source!r}: {error}") from error
    return markup


def on_page_content(content: str, page: Any, **_: Any) -> str:
    """Replace every marked formula of the page by its MathML; a displayed one in a div that scrolls when wide."""
    where = page.file.src_uri
    content = DISPLAY.sub(lambda m: f'<div class="math-display">{mathml(m.group(1), "block", where)}</div>', content)
    return INLINE.sub(lambda m: mathml(m.group(1), "inline", where), content)
