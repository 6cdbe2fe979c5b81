"""A run's answers as the user reads them: the HTML of a run's status, warnings and values (name,
value, unit, mark), in that order, each number `shown` as every front end prints it."""
from html import escape

from mechopt.kit.result import shown


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
    rows = "".join(f"<tr><td>{escape(name)}</td><td title='{value!r}'>{escape(shown(value))}</td>"
                   f"<td>{escape(unit)}</td><td>{escape(mark)}</td></tr>"
                   for name, value, unit, mark in run.value_rows())
    if not rows:
        return "<p>no values (the solver found none to report)</p>"
    return ("<div class='scroll'><table class='values'><tr><th>value</th><th>computed</th><th>unit</th>"
            f"<th>mark</th></tr>{rows}</table></div>")
