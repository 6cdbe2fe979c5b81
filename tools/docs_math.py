"""mkdocs hook (mkdocs.yml, `hooks:`): the pages' equations as MathML, written at build time.

pymdownx.arithmatex (generic mode) leaves ``\\( ... \\)`` in ``<span class="arithmatex">`` and
``\\[ ... \\]`` in ``<div class="arithmatex">``; each becomes MathML here (latex2mathml), which
browsers render themselves (MathML Core: Chromium 109+, Firefox, Safari). The site thus shows its
equations offline, from a folder or a mail attachment, and loads no script from anywhere (it
loaded MathJax from a CDN: offline, a reader saw raw TeX). The TeX stays in each formula's
``alttext`` for copying and for screen readers.
"""
import html
import re

from latex2mathml.converter import convert

MATH = re.compile(r'<(span|div) class="arithmatex">\s*\\([(\[])(.*?)\\[)\]]\s*</\1>', re.S)
# latex2mathml knows `align*` (unnumbered), whose rows and columns `aligned` (inside display math) has too
SAME_ROWS = {"{aligned}": "{align*}"}


def mathml(tex: str, *, block: bool) -> str:
    """One formula (TeX as written in the page) as a <math> element."""
    for old, new in SAME_ROWS.items():
        tex = tex.replace(old, new)
    element = convert(tex.strip(), display="block" if block else "inline")
    return element.replace("<math ", f'<math alttext="{html.escape(" ".join(tex.split()), quote=True)}" ', 1)


def to_mathml(match) -> str:
    tag, opener, tex = match.groups()
    return f'<{tag} class="arithmatex">{mathml(html.unescape(tex), block=opener == "[")}</{tag}>'


def on_page_content(html_text: str, **_) -> str:
    return MATH.sub(to_mathml, html_text)
