r"""User text in a figure, drawn as written.

Matplotlib reads any text holding two unescaped `$` as mathtext, so an operation named `$x^$` or
`$\frac{` fails with a ParseSyntaxException when the figure is drawn, after the solve (the answer
is lost), and `$a_b$` is quietly drawn as a formula. Every name a user or a table chooses (scene
ids, operations, events, groups, mechanisms, sweep keys and outputs, statuses read from a table)
goes through `literal` before it reaches a figure; the package's own labels are written in the
figure modules and may use mathtext on purpose. Outside mathtext only `$` is special (`_`, `^`,
`%`, `{` and `\` are drawn as they are), so `$` is the one character escaped.
"""

__all__ = ["literal"]


def literal(text) -> str:
    r"""`text` (any object, as `str` shows it) escaped so that matplotlib draws it character for
    character: every `$` becomes `\$`, which matplotlib draws as `$` and never pairs into math.

    >>> print(literal("$x^$ feed"))
    \$x^\$ feed
    >>> from matplotlib import cbook
    >>> cbook.is_math_text(literal(r"$a_b$ and \$"))
    False
    """
    return str(text).replace("$", r"\$")
