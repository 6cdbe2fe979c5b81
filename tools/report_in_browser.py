"""Look at `mechopt report`'s page in a real browser (headless Chromium from the distribution's
packages: `apt-get install chromium`) at a laptop's and a phone's width, as a designer would.

    python tools/report_in_browser.py out/report/index.html [--width 1280] [--screenshot shot.png]

Measures, in the rendered page: horizontal overflow (the page wider than the window), images that
did not load, the smallest text, how far each figure is shrunk (its axis labels, drawn at about
14 px in the PNG, scale with it) and the tallest table row. Prints them as JSON; exits 1 when the
page overflows, an image is broken, text is below 11 px, a table row is taller than 300 px (a
table squeezed into a phone's width, a word a line) or, at a laptop's width, a figure is shown
below 60 % of its size (on a phone a figure is shrunk to the screen and opened full screen by a tap).

The page is laid out in an iframe of the width asked for: headless Chromium will not make its
window narrower than 500 px, and an iframe's document has its own viewport (its media queries,
`innerWidth` and overflow are the page's own at that width).
"""
import argparse
import html
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

MEASURE = """<script>
window.addEventListener('load', () => {
  const imgs = [...document.images];
  const sizes = [...document.querySelectorAll('body *')]
    .filter(e => e.offsetParent !== null && [...e.childNodes].some(n => n.nodeType === 3 && n.textContent.trim()))
    .map(e => parseFloat(getComputedStyle(e).fontSize));
  const scales = imgs.filter(i => i.naturalWidth > 0).map(i => i.clientWidth / i.naturalWidth);
  const rows = [...document.querySelectorAll('tr')].filter(r => r.offsetParent !== null).map(r => r.offsetHeight);
  const out = {window_px: window.innerWidth, page_px: document.documentElement.scrollWidth,
               images: imgs.length, broken: imgs.filter(i => !i.complete || i.naturalWidth === 0).length,
               smallest_text_px: Math.min(...sizes), smallest_figure_scale: Math.min(...scales, 1),
               tallest_row_px: Math.max(0, ...rows)};
  const pre = parent.document.createElement('pre'); pre.id = 'mechopt-metrics';
  pre.textContent = JSON.stringify(out); parent.document.body.appendChild(pre);
});
</script>"""

HOST = "<!doctype html><html><body style='margin:0'><iframe style='border:0;width:{width}px;height:900px' " \
       "srcdoc=\"{page}\"></iframe></body></html>"

LIMITS = {"smallest_text_px": 11.0, "smallest_figure_scale": 0.6}
# a table row taller than this reads as a column of single words: a narrow screen scrolls the table instead
TALLEST_ROW_PX = 300
LAPTOP_PX = 1000          # from this width on a figure must be shown near its full size


def browser() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome-headless-shell"):
        if shutil.which(name):
            return shutil.which(name)
    raise SystemExit("no Chromium found: apt-get install chromium")


def measure(page: Path, width: int = 1280, screenshot: Path | None = None) -> dict:
    """Render the page headless at `width` px (in an iframe of that width) and return what MEASURE found."""
    text = page.read_text(encoding="utf-8").replace("</body>", MEASURE + "</body>")
    host = HOST.format(width=width, page=html.escape(text, quote=True))
    base = [browser(), "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
            f"--window-size={max(width, 500) + 20},900", "--virtual-time-budget=20000"]
    with tempfile.TemporaryDirectory() as tmp:
        probe = Path(tmp) / "probe.html"
        probe.write_text(host, encoding="utf-8")
        dom = subprocess.run(base + ["--dump-dom", probe.as_uri()], capture_output=True, text=True, timeout=300)
        if screenshot is not None:
            subprocess.run(base + [f"--screenshot={Path(screenshot).resolve()}", probe.as_uri()],
                           capture_output=True, timeout=300, check=True)
    found = re.search(r"<pre id=\"mechopt-metrics\">(.*?)</pre>", dom.stdout, flags=re.S)
    if not found:
        raise SystemExit(f"the browser gave no measurement ({dom.returncode}): {dom.stderr[-500:]}")
    return json.loads(found.group(1).replace("&quot;", '"'))


def problems(metrics: dict) -> list[str]:
    out = []
    if metrics["page_px"] > metrics["window_px"]:
        out.append(f"the page is {metrics['page_px']} px wide in a {metrics['window_px']} px window")
    if metrics["broken"]:
        out.append(f"{metrics['broken']} of {metrics['images']} images did not load")
    if metrics["tallest_row_px"] > TALLEST_ROW_PX:
        out.append(f"a table row is {metrics['tallest_row_px']} px tall (at most {TALLEST_ROW_PX})")
    for key, limit in LIMITS.items():
        if key == "smallest_figure_scale" and metrics["window_px"] < LAPTOP_PX:
            continue
        if metrics[key] < limit:
            out.append(f"{key} = {metrics[key]:.3g} < {limit}")
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("page", type=Path)
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--screenshot", type=Path)
    args = parser.parse_args(argv)
    metrics = measure(args.page, args.width, args.screenshot)
    print(json.dumps(metrics, indent=2))
    bad = problems(metrics)
    for line in bad:
        print(f"problem: {line}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
