"""hammesh.plot.cycle: headless, atomic pictures of meshes and their cycles."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import numpy as np
import pytest

import hammesh.plot as hplot
from hammesh.errors import InvalidMeshError
from hammesh.plot import cycle as cycle_module


def _image(path):
    from matplotlib.image import imread

    img = imread(path)
    assert img.ndim == 3 and img.shape[0] > 100 and img.shape[1] > 100
    return img[..., :3]


def _hue_bins(rgb: np.ndarray) -> set[int]:
    """Hue bins (of 12) holding at least 20 clearly coloured pixels."""
    from matplotlib.colors import rgb_to_hsv

    hsv = rgb_to_hsv(rgb.reshape(-1, 3))
    coloured = hsv[(hsv[:, 1] > 0.4) & (hsv[:, 2] > 0.3)]
    bins, counts = np.unique((coloured[:, 0] * 12).astype(int) % 12, return_counts=True)
    return set(bins[counts >= 20].tolist())


@pytest.fixture
def captured(monkeypatch):
    """The figures plot functions save, kept for inspection."""
    figures = []
    real = cycle_module._save

    def keep(fig, path, dpi):
        figures.append(fig)
        real(fig, path, dpi)

    monkeypatch.setattr(cycle_module, "_save", keep)
    return figures


def test_exports():
    assert hplot.__all__ == ["plot_cycle", "plot_mesh"]


def test_plot_cycle_png(tmp_path, hexagon, captured):
    path = tmp_path / "cycle.png"
    hplot.plot_cycle(hexagon, path)
    assert os.listdir(tmp_path) == ["cycle.png"]
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    img = _image(path)
    assert img.std() > 0
    # the cycle itself (left part of the picture, away from the colorbar) has several hues
    assert len(_hue_bins(img[:, : img.shape[1] // 2])) >= 2

    (fig,) = captured
    ax, cax = fig.axes
    assert cax.get_ylabel() == "position along cycle"
    assert "6 triangles, 1 cycle" in ax.get_title()
    (path_lines,) = [c for c in ax.collections if c.get_array() is not None]
    assert len(path_lines.get_segments()) == 6
    colours = np.unique(np.round(path_lines.get_colors(), 6), axis=0)
    assert len(colours) == 6  # one colour per position
    assert not ax.axison and ax.get_aspect() == 1.0


def test_cycle_segments_close_each_run(two_cycles):
    segments = cycle_module.cycle_segments(two_cycles)
    centroids = two_cycles.points[two_cycles.triangles].mean(axis=1)
    assert segments.shape == (10, 2, 2)
    np.testing.assert_allclose(segments[:, 0], centroids)
    np.testing.assert_allclose(segments[4, 1], centroids[5])
    np.testing.assert_allclose(segments[5, 1], centroids[0])  # first cycle closes
    np.testing.assert_allclose(segments[9, 1], centroids[6])  # second cycle closes


def test_two_cycles_title_and_custom_title(tmp_path, two_cycles, captured):
    hplot.plot_cycle(two_cycles, tmp_path / "two.png", title="Two fans", dpi=80)
    title = captured[0].axes[0].get_title()
    assert title.splitlines() == ["Two fans", "10 triangles, 2 cycles"]
    assert _image(tmp_path / "two.png").std() > 0


@pytest.mark.parametrize("suffix", [".pdf", ".svg"])
def test_vector_formats(tmp_path, hexagon, suffix):
    hplot.plot_cycle(hexagon, tmp_path / f"c{suffix}")
    assert (tmp_path / f"c{suffix}").stat().st_size > 1000
    assert os.listdir(tmp_path) == [f"c{suffix}"]


def test_plot_mesh(tmp_path, two_cycles, captured):
    hplot.plot_mesh(two_cycles.as_mesh(), tmp_path / "mesh.png", title="plain")
    img = _image(tmp_path / "mesh.png")
    assert img.std() > 0
    assert "10 triangles" in captured[0].axes[0].get_title()


def test_large_mesh_branch_skips_grey_edges(tmp_path, make_strip, monkeypatch, captured):
    monkeypatch.setattr(cycle_module, "LARGE_MESH", 10)
    hplot.plot_cycle(make_strip(20), tmp_path / "big.png")
    ax = captured[0].axes[0]
    assert len(ax.collections) == 2  # constrained edges + cycle, no grey mesh edges
    assert all(c.get_rasterized() for c in ax.collections)
    assert _image(tmp_path / "big.png").std() > 0


def test_failed_save_leaves_nothing(tmp_path, hexagon, monkeypatch):
    from matplotlib.figure import Figure

    def boom(self, fname, **kwargs):
        with open(fname, "wb") as f:
            f.write(b"\x89PNG half")
        raise OSError("simulated")

    target = tmp_path / "c.png"
    target.write_bytes(b"old")
    monkeypatch.setattr(Figure, "savefig", boom)
    with pytest.raises(OSError, match="simulated"):
        hplot.plot_cycle(hexagon, target)
    assert os.listdir(tmp_path) == ["c.png"] and target.read_bytes() == b"old"


def test_invalid_mesh_rejected(tmp_path, hexagon):
    import dataclasses

    bad = dataclasses.replace(hexagon, triangles=np.where(hexagon.triangles == 2, 50, hexagon.triangles))
    with pytest.raises(InvalidMeshError, match="50"):
        hplot.plot_cycle(bad, tmp_path / "x.png")
    assert os.listdir(tmp_path) == []


def test_threads_plot_concurrently(tmp_path, hexagon, two_cycles):
    errors = []

    def run(i):
        try:
            hplot.plot_cycle(hexagon if i % 2 else two_cycles, tmp_path / f"t{i}.png", dpi=60)
        except Exception as exc:  # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert sorted(os.listdir(tmp_path)) == [f"t{i}.png" for i in range(6)]
    for i in range(6):
        assert _image(tmp_path / f"t{i}.png").std() > 0


def test_headless_without_pyplot(tmp_path):
    code = (
        "import sys\n"
        "import hammesh.plot\n"
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported at import time'\n"
        "import numpy as np\n"
        "from hammesh.mesh import Mesh\n"
        "hammesh.plot.plot_mesh(Mesh(np.array([[0., 0], [1, 0], [0, 1]]), np.array([[0, 1, 2]])), sys.argv[1])\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot imported'\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MPLBACKEND")}
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    result = subprocess.run([sys.executable, "-c", code, str(tmp_path / "h.png")],
                            capture_output=True, text=True, env=env, timeout=120)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "h.png").exists()


@pytest.mark.slow
def test_large_mesh_renders_quickly(tmp_path, make_strip):
    import time

    mesh = make_strip(110_000)  # 220k triangles, above LARGE_MESH
    # CPU time of this process, not wall time: the rendering is single-threaded, and a
    # loaded machine (CI, or tests run beside other work) stretched the wall time past
    # the limit without the renderer getting any slower
    start = time.process_time()
    hplot.plot_cycle(mesh, tmp_path / "large.png", dpi=100)
    assert time.process_time() - start < 30
    assert _image(tmp_path / "large.png").std() > 0
