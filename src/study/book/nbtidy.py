"""What the builder does to a chapter papermill has just executed, before the book renders it.

- **One parameters cell.** papermill adds a cell tagged ``injected-parameters`` after the chapter's own
  ``parameters`` cell. The reader should see one cell, with the values this copy ran with: the
  injected values are written into the chapter's cell (``preset = "smoke"  # set by study book;
  default "paper"``) and the injected cell is tagged ``remove-cell``. The executed notebook keeps it.
- **Figures are images.** A figure shown by a kernel whose matplotlib backend is not the inline one
  comes out as its text, ``<Figure size 640x480 with 1 Axes>``, and the book would print that text
  where the figure belongs. :func:`figures_as_text` finds such outputs so the build can fail on them.
- **A small build says so.** A chapter executed with any preset but ``paper`` carries, under its title, a warning
  that its numbers are that preset's, not the study's (:func:`preset_warning`): a smoke build's verdicts are a
  test's, and a reader who opens its pages must not take them for the study's.
- **No library banners.** pybullet's C code prints ``pybullet build time: ...`` when a kernel first imports it,
  past Python's redirection in a Jupyter kernel; :func:`drop_banners` removes those lines from the cells'
  printed output, so a page that only reads Bullet's results does not show them.
"""

from __future__ import annotations

import json
import re
from typing import Any

FIGURE_TEXT = re.compile(r"^<Figure size [\d.]+x[\d.]+ with \d+ Axes>$")
"""matplotlib's text for a figure: what a figure turns into without an image behind it."""
BANNER = re.compile(r"^pybullet build time: .*$\n?", re.MULTILINE)
"""A line a library prints on import, not the cell's output."""
_ASSIGN = re.compile(r"^(?P<name>[A-Za-z_]\w*)\s*=\s*(?P<value>.*?)(?P<comment>\s*#.*)?$")


def _tags(cell: Any) -> list[str]:
    return cell.setdefault("metadata", {}).setdefault("tags", [])


def _literal(value: Any) -> str:
    return json.dumps(value) if isinstance(value, str) else repr(value)


def show_parameters_once(nb: Any, injected: dict[str, Any]) -> Any:
    """Write ``injected`` into ``nb``'s ``parameters`` cell and hide papermill's injected cell (in place)."""
    for cell in nb.cells:
        tags = _tags(cell)
        if "injected-parameters" in tags and "remove-cell" not in tags:
            tags.append("remove-cell")
        if "parameters" not in tags:
            continue
        lines = []
        for line in cell.source.splitlines():
            m = _ASSIGN.match(line)
            if m and m["name"] in injected and m["value"] != _literal(injected[m["name"]]):
                line = f"{m['name']} = {_literal(injected[m['name']])}  # set by `study book`; default {m['value']}"
            lines.append(line)
        cell.source = "\n".join(lines)
    return nb


def figures_as_text(nb: Any) -> list[int]:
    """Indices of the code cells with an output that is a figure's text and no image."""
    bad = []
    for i, cell in enumerate(nb.cells):
        for out in cell.get("outputs", []):
            data = out.get("data", {})
            texts = [v for k, v in data.items() if k.endswith("text/plain")]
            images = [k for k in data if k.split("/")[-2:-1] == ["image"] or k.endswith(("image/png", "image/svg+xml"))]
            if not images and any(FIGURE_TEXT.match(str(t).strip()) for t in texts):
                bad.append(i)
                break
    return bad


STUDY_PRESET = "paper"
"""The preset whose numbers are the study's."""
PRESET_WARNING = """```{{warning}}
A **{preset}** preset build, for tests: not the study's numbers.
```"""
"""What a page built with another preset says under its title."""


def preset_warning(nb: Any, preset: str) -> Any:
    """``nb`` with :data:`PRESET_WARNING` under the title of its first Markdown cell, unless ``preset`` is the
    study's own (in place)."""
    if preset == STUDY_PRESET:
        return nb
    for cell in nb.cells:
        if cell.cell_type != "markdown":
            continue
        lines = cell.source.split("\n")
        at = next((k for k, line in enumerate(lines) if line.startswith("# ")), -1)
        cell.source = "\n".join([*lines[: at + 1], "", PRESET_WARNING.format(preset=preset), "", *lines[at + 1 :]])
        break
    return nb


def drop_banners(nb: Any) -> Any:
    """Remove :data:`BANNER` lines from ``nb``'s printed (stream) outputs, and outputs left empty (in place)."""
    for cell in nb.cells:
        if "outputs" not in cell:
            continue
        kept = []
        for out in cell["outputs"]:
            if out.get("output_type") == "stream":
                text = out.get("text", "")
                out["text"] = BANNER.sub("", "".join(text) if isinstance(text, list) else text)
                if not out["text"]:
                    continue
            kept.append(out)
        cell["outputs"] = kept
    return nb
