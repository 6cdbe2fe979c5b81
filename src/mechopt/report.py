"""`mechopt report`: one static HTML page of what the registry reproduces, and how it looks.

The page holds the validation table (every scene's expectations: published or derived value
against the computed one, calibrations marked as such, not counted as reproductions), each scene's
assumed and calibrated parameters with their reasons, each scene's figures (`mechopt.figures.plot_run`),
the maps of any sweep tables given (`mechopt.figures.sweep`) and the accuracy-vs-time plots that
`mechopt bench` left in a folder (benchmarks are not re-run here: some take minutes). Every image
is embedded in the page (base64 PNG), so the one file opens from disk, or as a mail attachment,
with no server and nothing beside it.
"""
import base64
import html
import tempfile
from collections.abc import Callable, Sequence
from datetime import datetime, timezone
from pathlib import Path

from mechopt import __version__, registry, verdicts
from mechopt.answers import answers_html
from mechopt.drivers import set_mostly_by, steps_of
from mechopt.figures import plot_run
from mechopt.figures.sweep import plot_sweep
from mechopt.files import write_text_atomic
from mechopt.kit.result import shown
from mechopt.sweep import describe_axes, read_table, scene_hash
from mechopt.units import unit_of

__all__ = ["write_report"]

_STYLE = """body{font-family:system-ui,sans-serif;max-width:1180px;margin:1.5em auto;padding:0 1em;color:#222;
line-height:1.4}h1,h2,h3{overflow-wrap:anywhere}table{border-collapse:collapse;font-size:14px}
td,th{border:1px solid #ccc;padding:3px 6px;text-align:left;vertical-align:top}table.wide{width:100%;min-width:50em}
.long{display:block;overflow-wrap:anywhere;min-width:min(24em,75vw)}th{background:#f0f0f0}.values td:nth-child(2){text-align:right}
.ok{color:#176117}.fail{color:#b00020;font-weight:bold}.cal{color:#8a5a00}.miss{color:#8a3a00;font-weight:bold}
.scroll{overflow-x:auto;max-width:100%}.warnings{color:#8a3a00}
figure{margin:10px 0;font-size:13px;color:#555}img{width:100%;height:auto;border:1px solid #ddd;cursor:zoom-in}
img.zoom{position:fixed;inset:0;margin:auto;width:auto;max-width:98vw;max-height:98vh;z-index:9;cursor:zoom-out;
background:#fff;box-shadow:0 0 0 100vmax rgba(0,0,0,.6)}details{margin:0.4em 0}summary{cursor:pointer}
nav li{margin:2px 0}code,figcaption,p{overflow-wrap:anywhere}"""
_SCRIPT = ("<script>document.addEventListener('click',e=>{if(e.target.tagName==='IMG')"
           "e.target.classList.toggle('zoom')})</script>")


def write_report(out_dir, *, scenes: Sequence | None = None, runs: Sequence | None = None, bench_dir=None,
                 sweeps: Sequence = (), progress: Callable[[str], None] | None = None,
                 command: str | None = None) -> Path:
    """Run the scenes (all by default), draw their figures and write ``out_dir/index.html``.

    Parameters
    ----------
    out_dir : folder for the page (created); the page is the only file written there.
    scenes : the scenes to include (``registry.find(id)`` each); default every scene.
    runs : scenes already solved (``registry.run``), shown as they are instead of `scenes`.
    bench_dir : folder of `mechopt bench` outputs; its PNG files are embedded when it exists.
    sweeps : Parquet tables written by `mechopt sweep --out`; their maps are embedded.
    progress : called with one line per scene run.
    command : the command that made the page, shown with the version, date and scene hashes.

    Returns
    -------
    Path of the HTML page.
    """
    tables = [(Path(p), *read_table(p)) for p in sweeps]        # a file of no sweep fails before any work
    out_dir = Path(out_dir)
    if runs is None:
        runs = []
        for scene in scenes if scenes is not None else registry.all_scenes():
            if progress:
                progress(f"running {scene.id} ...")
            runs.append(registry.run(scene, drivers=True))
    with tempfile.TemporaryDirectory() as scratch:
        parts = ["<h1>mechopt: validation report</h1>", _provenance(runs, command), _contents(runs),
                 "<h2 id='validation'>Validation</h2>", _validation(runs),
                 "<h2>Scenes</h2>", *(_scene_section(run, Path(scratch) / f"scene_{k}") for k, run in enumerate(runs))]
        if tables:
            parts += ["<h2>What-if maps</h2>",
                      *(_sweep_section(*t, Path(scratch) / f"sweep_{k}") for k, t in enumerate(tables))]
        parts += ["<h2>Accuracy against time</h2>", _bench(bench_dir)]
    page = out_dir / "index.html"
    write_text_atomic(page, "<!doctype html><html><head><meta charset='utf-8'><title>mechopt report</title>"
                      "<meta name='viewport' content='width=device-width,initial-scale=1'>"
                      f"<style>{_STYLE}</style></head><body>\n" + "\n".join(parts) + f"\n{_SCRIPT}</body></html>\n")
    return page


CSS_OF_VERDICT = {"calibrated": "cal", "alternative": "cal", "reproduced": "ok", "derived": "ok", "follows": "ok"}


def _validation(runs):
    """The counts per verdict and the misses first; every check in a table folded below."""
    checks = [c for r in runs for c in r.checks]
    counts = verdicts.tally(checks)
    rows, misses = [], []
    for run in runs:
        assumed = sum(m == "assumed" for m in run.scene.marks().values())
        for c in run.checks:
            css = "fail" if not c.ok else CSS_OF_VERDICT.get(c.verdict, "miss")
            verdict = f"<span class='{css}'>{_e(c.label if c.ok else 'FAIL (' + c.label + ')')}</span>"
            why = f"<span class='long'>{_e(c.reason or c.where)}</span>"
            rows.append((verdicts.VERDICTS.index(c.verdict),
                         [_e(run.scene.id), _e(c.name), _e(c.kind), _e(c.expected), _e(shown(c.got)), verdict, why,
                          str(assumed)]))
            if c.verdict in verdicts.MISSES:
                misses.append((verdicts.VERDICTS.index(c.verdict),
                               [_e(run.scene.id), _e(c.name), _e(c.expected), _e(shown(c.got)), verdict, why]))
    rows.sort(key=lambda row: min(row[0], len(verdicts.MISSES)))        # the misses first
    misses.sort(key=lambda row: row[0])
    tallies = _table(["verdict", "checks"], [[_e(v.replace("_", " ")), str(n)] for v, n in counts.items() if n])
    return (f"<p><b>{_e(verdicts.summary_line(checks))}</b></p>{tallies}"
            + (f"<h3>Misses ({len(misses)})</h3>" + _table(["case", "quantity", "expected (source)", "computed",
                                                            "verdict", "why"], [m[1] for m in misses], wide=True)
               if misses else "<p>no misses: every check is reproduced, an alternative reading, calibrated, derived "
               "or follows</p>")
            + f"<details><summary>every check ({len(checks)}), misses first</summary>"
            + _table(["case", "quantity", "kind", "expected (source)", "computed", "verdict", "where / why missed",
                      "assumed params"], [r[1] for r in rows], wide=True) + "</details>")


def _provenance(runs, command):
    """Which mechopt made the page, when, by what command, from which scene files."""
    hashes = [[_e(r.scene.id), f"<code>{scene_hash(r.scene)[:16]}</code>", f"<span class='long'>{_e(str(r.scene.path))}</span>"]
              for r in runs]
    return (f"<p>mechopt {_e(__version__)}, {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC"
            + (f"; made by <code>{_e(command)}</code>" if command else "") + "</p>"
            + "<details><summary>scene files (sha256)</summary>" + _table(["scene", "sha256", "file"], hashes)
            + "</details>")


def _contents(runs):
    """The scenes by mechanism (the first part of the id), each a link to its section."""
    groups = {}
    for run in runs:
        groups.setdefault(run.scene.id.split("/", 1)[0], []).append(run)
    items = "".join(f"<li><b>{_e(name)}</b>: " + ", ".join(
        f"<a href='#{_e(r.scene.id.replace('/', '_'))}'>{_e(r.scene.id.split('/', 1)[-1])}</a>" for r in group)
        + "</li>" for name, group in groups.items())
    return f"<nav><h2>Contents</h2><ul><li><a href='#validation'>validation</a></li>{items}</ul></nav>"


def _scene_section(run, folder):
    """Its status, values and warnings first, then how it was made, then its figures (drawn into
    `folder`, a private scratch folder: named by number, never by the scene's id)."""
    scene, r = run.scene, run.result
    slug = scene.id.replace("/", "_")
    marked = [(k, p.value, p.mark, p.why + (f" (fitted to {p.on})" if p.on else ""))
              for k, p in scene.spec.params.items() if p.mark != "given"]
    images = "".join(_image(p) for p in plot_run(run, folder))
    return (f"<h3 id='{_e(slug)}'>{_e(scene.id)}: {_e(scene.spec.title)}</h3>"
            + answers_html(run)
            + "".join(f"<p>{_e(w)}</p>" for w in set_mostly_by(r.diagnostics.get("drivers", {}))
                      + steps_of(r.diagnostics.get("drivers", {})))
            + f"<p><i>{_e(scene.spec.source)}</i><br>build {r.timing.build_s:.4f} s, solve {r.timing.solve_s:.4f} s</p>"
            + (f"<details><summary>{len(marked)} assumed / calibrated parameters</summary>"
               + _table(["parameter", "value", "unit", "mark", "why"],
                        [[_e(k), _e(shown(v)), _e(unit_of(k)), _e(m), f"<span class='long'>{_e(w)}</span>"]
                         for k, v, m, w in marked])
               + "</details>" if marked else "<p>every parameter given by the source</p>")
            + (images or "<p>no figures for this model</p>"))


def _sweep_section(path, table, meta, folder):
    statuses = table.column("status").to_pylist()
    counts = ", ".join(f"{statuses.count(s)} {s}" for s in sorted(set(statuses)))
    scene = next((s for s in registry.all_scenes() if s.id == meta["case"]), None)
    stale = ("<p class='fail'>this case is not in the registry (a scene file of your own? add its folder "
             "with --cases DIR); the maps are drawn from the table alone</p>" if scene is None
             else "<p class='fail'>swept an earlier version of the scene file (its sha256 differs): "
                  "the maps may not match the validation above</p>" if scene_hash(scene) != meta["scene_sha256"]
             else "")
    spec = meta["spec"]
    drawn = "".join(_image(p) for p in plot_sweep(table, folder, scene=scene))
    return (f"<h3>{_e(meta['case'])}: {_e(path.name)}</h3>{stale}<p>{table.num_rows} variants ({_e(counts)}); "
            f"swept {_e(' '.join(describe_axes(spec)))}"
            + (f", {spec['samples']} samples, seed {spec['seed']}" if spec["random"] else "") + "</p>" + drawn)


def _bench(bench_dir):
    pngs = sorted(Path(bench_dir).glob("*.png")) if bench_dir and Path(bench_dir).is_dir() else []
    if not pngs:
        return f"<p>no `mechopt bench` output found{' in ' + _e(str(bench_dir)) if bench_dir else ''}; " \
               "run e.g. <code>mechopt bench cam-cutter --plot out/bench</code> first.</p>"
    return "".join(_image(png) for png in pngs)


def _image(png):
    """A PNG embedded in the page at full width (click: the whole window), captioned with its name."""
    data = base64.b64encode(Path(png).read_bytes()).decode("ascii")
    return (f"<figure><img src='data:image/png;base64,{data}' alt='{_e(Path(png).stem)}'>"
            f"<figcaption>{_e(Path(png).name)}</figcaption></figure>")


def _table(header, rows, *, wide=False):
    """A table in its own scrolling box: a wide one scrolls there, never the page."""
    head = "".join(f"<th>{h}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{x}</td>" for x in row) + "</tr>" for row in rows)
    table = "<table class='wide'>" if wide else "<table>"
    return f"<div class='scroll'>{table}<tr>{head}</tr>{body}</table></div>"


def _e(text):
    return html.escape(str(text), quote=True)
