"""Does every page of a built book fit its reader's screen? Screenshots of each page at a desktop's width and a
phone's, and whether any page's body is wider than its viewport (it would scroll sideways).

For every ``<book>/book/*.html`` and each width (1400 and 390 CSS pixels by default), a full-page screenshot in
``--out`` (``<page>-<width>.png``), and, where the document is wider than the viewport, the elements that reach
past its right edge (the widest first). Exit status 0 when no page scrolls sideways, 1 otherwise, 2 for a book or
browser that is not there.

Needs headless Chromium and Playwright's Python client, neither of which the project's environment holds (so it
is not part of ``make test``)::

    apt-get install chromium
    python -m venv /tmp/pw && /tmp/pw/bin/pip install playwright
    /tmp/pw/bin/python scripts/screenshots.py _build/html --out /tmp/shots
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

WIDTHS = (1400, 390)
"""CSS pixels: a desktop browser's window, and a phone's (an iPhone 12-15's 390)."""
HEIGHTS = {1400: 900, 390: 844}
"""The viewport's height at each width (the screenshot itself is of the whole page)."""
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
        "--disable-component-update", "--disable-sync"]
"""Chromium's flags on a machine without a display or a network."""
OVERFLOW = """() => {
  const w = window.innerWidth;
  const wide = [];
  for (const el of document.querySelectorAll('body *')) {
    const r = el.getBoundingClientRect();
    if (r.right > w + 1 && r.width > 0) {
      let box = el.parentElement, clipped = false;  // inside a box that scrolls or clips: it does not widen the page
      while (box && box !== document.body) {
        const s = getComputedStyle(box);
        if (['auto', 'scroll', 'hidden'].includes(s.overflowX)) { clipped = true; break; }
        box = box.parentElement;
      }
      if (!clipped) wide.push([el.tagName.toLowerCase() + (el.className ? '.' + String(el.className).split(' ')[0] : ''),
                               Math.round(r.right)]);
    }
  }
  wide.sort((a, b) => b[1] - a[1]);
  return {scroll: document.documentElement.scrollWidth, width: w, wide: wide.slice(0, 5)};
}"""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("html", type=Path, help="the built book's HTML folder (_build/html)")
    ap.add_argument("--out", type=Path, required=True, help="folder for the screenshots")
    ap.add_argument("--widths", type=int, nargs="+", default=list(WIDTHS), help="viewport widths, CSS pixels")
    ap.add_argument("--chromium", default=shutil.which("chromium") or "/usr/bin/chromium", help="the browser")
    a = ap.parse_args(argv)
    pages = sorted((a.html / "book").glob("*.html"))
    if not pages:
        print(f"screenshots: no pages in {a.html / 'book'}; build the book first", file=sys.stderr)
        return 2
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        print("screenshots: needs Playwright's Python client (pip install playwright)", file=sys.stderr)
        return 2
    if not Path(a.chromium).is_file():
        print(f"screenshots: no Chromium at {a.chromium}; apt-get install chromium, or pass --chromium", file=sys.stderr)
        return 2
    a.out.mkdir(parents=True, exist_ok=True)
    bad = 0
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=a.chromium, args=ARGS)
        for width in a.widths:
            page = browser.new_page(viewport={"width": width, "height": HEIGHTS.get(width, 900)})
            for html in pages:
                page.goto(html.resolve().as_uri())
                page.wait_for_load_state("load")
                page.screenshot(path=str(a.out / f"{html.stem}-{width}.png"), full_page=True)
                m = page.evaluate(OVERFLOW)
                scrolls = m["scroll"] > m["width"] + 1
                bad += scrolls
                where = "" if not scrolls else "; wider: " + ", ".join(f"{t} to {r} px" for t, r in m["wide"])
                print(f"{html.stem:12s} {width:5d} px: body {m['scroll']} px "
                      f"{'SCROLLS SIDEWAYS' if scrolls else 'fits'}{where}")
            page.close()
        browser.close()
    print(f"{bad} page views scroll sideways; screenshots in {a.out}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
