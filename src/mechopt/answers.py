"""A run's answers as HTML, where the report and a notebook show them: its status, its values
(name, value, unit, mark) and its warnings, in that order."""
from html import escape

SIGNIFICANT = 4          # digits shown (the sources print 4); the full value is the cell's tooltip


def answers_html(run) -> str:
    """Status line, warnings, then the values table of a Run."""
    r = run.result
    css = "ok" if run.ok else "fail"
    status = (f"<p class='status'>status <b class='{css}'>{escape(r.status.value)}</b>"
              + (f" ({escape(r.message)})" if r.message else "") + "</p>")
    return status + warnings_html(run) + values_html(run)


def warnings_html(run) -> str:
    said = run.result.warnings
    if not said:
        return ""
    return "<ul class='warnings'>" + "".join(f"<li>warning: {escape(str(w))}</li>" for w in said) + "</ul>"


def values_html(run) -> str:
    rows = "".join(f"<tr><td>{escape(name)}</td><td title='{value!r}'>{value:.{SIGNIFICANT}g}</td>"
                   f"<td>{escape(unit)}</td><td>{escape(mark)}</td></tr>"
                   for name, value, unit, mark in run.value_rows())
    if not rows:
        return "<p>no values (the solver found none to report)</p>"
    return ("<div class='scroll'><table class='values'><tr><th>value</th><th>computed</th><th>unit</th>"
            f"<th>mark</th></tr>{rows}</table></div>")
