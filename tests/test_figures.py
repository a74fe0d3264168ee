"""The book's figure style: class colours, and files that are byte-identical for the same figure."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pytest

from study import figures
from study.errors import ConfigError


def draw() -> plt.Figure:
    figures.use_style()
    fig, ax = plt.subplots()
    t = np.linspace(0.0, 2.0, 50)
    for name, e in (("light", 0.8), ("heavy", 0.3)):
        ax.plot(t, np.abs(np.sin(3 * t)) * np.exp(-t / e), color=figures.CLASS_COLORS[name], label=name)
    ax.set(xlabel="time (s)", ylabel="height z (m)", title="a figure")
    ax.legend()
    return fig


def test_class_colors_are_okabe_ito_blue_and_vermillion() -> None:
    assert figures.CLASS_COLORS == {"light": "#0072B2", "heavy": "#D55E00"}
    figures.use_style()
    cycle = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    assert [c.upper() for c in cycle[:2]] == ["#0072B2", "#D55E00"]


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_same_figure_gives_same_bytes(tmp_path: Path, suffix: str) -> None:
    a, b = tmp_path / f"a{suffix}", tmp_path / f"b{suffix}"
    fig = draw()
    figures.save(fig, a)
    plt.close(fig)
    fig = draw()
    figures.save(fig, b)
    plt.close(fig)
    assert a.read_bytes() == b.read_bytes()
    assert b"Matplotlib v" not in a.read_bytes() and b"<dc:date>" not in a.read_bytes()
    assert not list(tmp_path.glob(".*.tmp"))


def test_unknown_suffix_is_a_config_error(tmp_path: Path) -> None:
    fig = draw()
    with pytest.raises(ConfigError, match=r"\.jpeg"):
        figures.save(fig, tmp_path / "x.jpeg")
    plt.close(fig)
