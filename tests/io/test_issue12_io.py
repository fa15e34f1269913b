"""Issue 12 regressions in the library: readers, writers, paths, options, the numba cache."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.errors import (
    FileFormatError,
    HammeshError,
    InvalidMeshError,
    InvalidOptionError,
    NotPlanarError,
    OutputError,
)
from hammesh.io import check_outputs, read_mesh, read_points, read_polygon, write
from hammesh.io.atomic import atomic_path, remove_stale_temps
from hammesh.io.polygons import triangulate_cells
from hammesh.mesh import HamiltonianMesh, Mesh


def _area2(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    a, b, c = (points[tri[:, i]] for i in range(3))
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])


# quads and polygons (defect 2) --------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    k=st.integers(3, 12),
    radii=st.lists(st.floats(0.3, 1.0), min_size=12, max_size=12),
    turn=st.sampled_from([1, -1]),
)
def test_star_polygons_split_into_triangles_of_their_own_winding(k, radii, turn):
    """A star-shaped polygon (convex or not) becomes k - 2 triangles that all turn as
    it does and whose areas sum to its area: nothing lost, nothing folded."""
    angles = turn * 2 * np.pi * np.arange(k) / k
    r = np.array(radii[:k])
    pts = np.column_stack([r * np.cos(angles), r * np.sin(angles)])
    cell = np.arange(k)[None, :]
    tri, origin = triangulate_cells(pts, cell)
    assert tri.shape == (k - 2, 3) and (origin == 0).all()
    a2 = _area2(pts, tri)
    x, y = pts[:, 0], pts[:, 1]
    poly2 = np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    assert (np.sign(a2) == np.sign(poly2)).all()
    assert a2.sum() == pytest.approx(poly2, rel=1e-9, abs=1e-12)


def test_quads_in_3d_keep_the_normal():
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0], [0.3, 0.3, 0.0]])
    tri, _ = triangulate_cells(pts, np.array([[0, 1, 2, 3], [0, 1, 2, 4]]))
    normals = np.cross(pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]])
    assert (normals[:, 2] > 0).all()


def test_polygon_faces_of_an_off_file_are_triangulated(tmp_path):
    f = tmp_path / "p.off"
    f.write_text("OFF\n6 2 0\n0 0 0\n2 0 0\n3 1 0\n2 2 0\n0 2 0\n4 0 0\n5 0 1 2 3 4\n3 1 5 2\n")
    m = read_mesh(f)
    assert m.n_triangles == 4
    assert m.info["repairs"] == ["triangulated 1 5-gon (3 triangles)"]
    assert _area2(m.points, m.triangles).sum() / 2 == pytest.approx(5.0 + 1.0)


# constant z, OBJ, legacy VTK (legitimate inputs) --------------------------------------------


def test_constant_z_reads_as_planar_and_varying_z_names_the_range(tmp_path):
    pts = np.array([[0, 0, 5], [1, 0, 5], [0, 1, 5.0]])
    meshio.write(tmp_path / "a.vtu", meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))]))
    m = read_mesh(tmp_path / "a.vtu")
    assert m.points.shape == (3, 2) and m.info["repairs"]
    with pytest.raises(FileFormatError, match="strict"):
        read_mesh(tmp_path / "a.vtu", strict=True)
    pts[2, 2] = 7
    meshio.write(tmp_path / "b.vtu", meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(NotPlanarError, match="from 5 to 7"):
        read_mesh(tmp_path / "b.vtu")
    assert read_mesh(tmp_path / "b.vtu", dim=None).points.shape == (3, 3)


def test_obj_relative_indices_follow_the_specification(tmp_path):
    f = tmp_path / "r.obj"
    f.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nv 0 1 0\nf 1/1 3//2 -1/1/1\nvt 0 0\n")
    m = read_mesh(f)
    assert m.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]
    f.write_text("v 0 0 0\nf -1 -2 -3\n")
    with pytest.raises(FileFormatError, match=r"r\.obj:2: vertex index -2 refers to no vertex"):
        read_mesh(f)


def _pyvista():
    return pytest.importorskip("pyvista")  # the [vtk] extra: compared with VTK's own reader


def test_legacy_vtk_polydata_globe_matches_vtk():
    pv = _pyvista()
    from pyvista import examples

    path = Path(examples.__file__).parent / "globe.vtk"
    ours = read_mesh(path, dim=3)
    theirs = pv.read(path)
    assert np.array_equal(ours.points, np.asarray(theirs.points, dtype=np.float64))
    assert np.array_equal(ours.triangles, theirs.faces.reshape(-1, 4)[:, 1:])


@pytest.mark.parametrize("binary", [False, True])
def test_legacy_vtk_polydata_quads_strips_lines(tmp_path, binary):
    pv = _pyvista()
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0], [3, 0, 0], [3, 1, 0.0]])
    poly = pv.PolyData(pts, faces=np.array([4, 0, 1, 2, 3, 3, 1, 4, 5]), lines=np.array([3, 0, 1, 4]))
    strip = pv.PolyData(pts, strips=np.array([4, 4, 6, 5, 7]))
    f = tmp_path / "p.vtk"
    poly.save(f, binary=binary)
    m = read_mesh(f)
    assert m.n_triangles == 3 and m.info["repairs"] == ["triangulated 1 quad (2 triangles)"]
    assert m.segments.tolist() == [[0, 1], [1, 4]]
    assert (_area2(m.points, m.triangles) > 0).all()
    g = tmp_path / "s.vtk"
    strip.save(g, binary=binary)
    s = read_mesh(g)
    assert s.triangles.tolist() == [[4, 6, 5], [5, 6, 7]]  # windings kept, as VTK decodes strips
    assert (_area2(s.points, s.triangles) != 0).all()


def test_legacy_vtk_polydata_without_pyvista_classic_ascii(tmp_path):
    f = tmp_path / "c.vtk"
    f.write_text("# vtk DataFile Version 3.0\nhand\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n"
                 "0 0 0 1 0 0 1 1 0\n0 1 0\nPOLYGONS 2 7\n3 0 1 2\n2 0 2\nPOINT_DATA 4\n")
    assert read_mesh(f).segments.tolist() == [[0, 2]]  # a two-corner polygon is an edge
    f.write_text("# vtk DataFile Version 3.0\nhand\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n"
                 "0 0 0 1 0 0 1 1 0\n0 1 0\nPOLYGONS 2 8\n3 0 1 2\n3 0 2\nPOINT_DATA 4\n")
    with pytest.raises(FileFormatError, match="POLYGONS"):
        read_mesh(f)
    f.write_text("# vtk DataFile Version 3.0\nhand\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n"
                 "0 0 0 1 0 0 1 1 0\n0 1 0\nPOLYGONS 2 8\n3 0 1 2\n3 0 2 3\nPOINT_DATA 4\n")
    assert read_mesh(f).triangles.tolist() == [[0, 1, 2], [0, 2, 3]]


# Triangle files: counts and markers (defects 4, 5) ------------------------------------------


def test_declared_counts_are_checked_before_allocating(tmp_path):
    (tmp_path / "h.node").write_text("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n")
    (tmp_path / "h.ele").write_text("100000000000 3 0\n1 1 2 3\n")
    with pytest.raises(FileFormatError, match="declares 100000000000 triangles"):
        read_mesh(tmp_path / "h.ele")


def test_markers_beyond_32_bits_msh_is_an_error_not_an_overflow(tmp_path):
    m = Mesh(np.array([[0.0, 0], [1, 0], [0, 1]]), np.array([[0, 1, 2]]), segments=np.array([[0, 1]]),
             segment_markers=np.array([2**40]))
    with pytest.raises(InvalidMeshError, match="32-bit"):
        write(m, tmp_path / "m.msh")
    write(m, tmp_path / "m.vtu")  # VTU holds int64: kept exactly
    assert read_mesh(tmp_path / "m.vtu").segment_markers.tolist() == [2**40]
    with pytest.raises(hammesh.InvalidDomainError, match="32-bit"):
        hammesh.Domain([[0, 0], [1, 0], [0, 1]], [[0, 1], [1, 2], [2, 0]], segment_markers=[1, 2**40, 1])


# point and polygon files (defects 5, 10) ---------------------------------------------------


@pytest.mark.parametrize("arr, match", [
    (np.zeros((0, 2)), "no points"),
    (np.array([["a", "b"]]), "real numbers"),
    (np.array([[0, 0], [1, 1j]]), "complex"),
    (np.array([[0, 0], [np.inf, 1]]), "not finite"),
])
def test_npy_point_files_are_checked(tmp_path, arr, match):
    np.save(tmp_path / "p.npy", arr)
    with pytest.raises(FileFormatError, match=match):
        read_points(tmp_path / "p.npy")


@pytest.mark.parametrize("name, data, match", [
    ("l.geojson", b"[1, 2]", "JSON list"),
    ("n.geojson", b"null", "JSON NoneType"),
    ("r.geojson", b'{"type": "Polygon", "coordinates": [5]}', "list of"),
    ("d.geojson", b"[" * 100_000 + b"]" * 100_000, "nested too deeply"),
    ("u.wkt", "POLYGON ((0 0, 1 0, 0 1)) \u00e9".encode("latin-1"), "not UTF-8"),
])
def test_polygon_files_malformed(tmp_path, name, data, match):
    (tmp_path / name).write_bytes(data)
    with pytest.raises(FileFormatError, match=match):
        read_polygon(tmp_path / name)


# output paths (defects 1, 6, 9, 10) ---------------------------------------------------------


def test_check_outputs(tmp_path):
    src = tmp_path / "a.poly"
    src.write_text("x")
    check_outputs({"-o": tmp_path / "b.vtu", "--report": tmp_path / "b.json"}, [src])
    for outputs, match in [
        ({"-o": tmp_path / "a.ele"}, r"a\.(node|poly): is an input file \(written with a\.ele\)"),
        ({"-o": tmp_path / "sub" / ".." / "a.poly"}, "is an input file|does not exist"),
        ({"-o": tmp_path / "x.json", "--strip": tmp_path / "x.json"}, "given twice"),
        ({"-o": tmp_path / "nodir" / "x.vtu"}, "does not exist"),
        ({"-o": tmp_path}, "is a directory"),
        ({"-o": tmp_path / ("y" * 300 + ".vtu")}, "longer than 255"),
    ]:
        with pytest.raises(OutputError, match=match):
            check_outputs(outputs, [src])
    check_outputs({"-o": tmp_path / "new" / "deeper" / "m.vtu"}, make_dirs=[tmp_path / "new" / "deeper"])


def test_temp_name_fits_a_255_byte_target(tmp_path):
    target = tmp_path / ("z" * 251 + ".vtu")
    with atomic_path(target) as tmp:
        assert len(os.fsencode(tmp.name)) <= 255 and tmp.suffix == ".vtu"
        tmp.write_text("ok")
    assert target.read_text() == "ok"


def test_stale_temps_only_of_dead_writers_are_removed(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f".a.vtu.tmp-{dead.pid}-00ff00ff.vtu"
    mine = tmp_path / f".a.vtu.tmp-{os.getpid()}-00ff00ff.vtu"
    other = tmp_path / ".a.vtu.tmp-notapid.vtu"
    for f in (stale, mine, other):
        f.write_text("x")
    assert remove_stale_temps(tmp_path) == [stale]
    assert mine.exists() and other.exists()


def test_write_errors_are_output_errors_naming_the_target(tmp_path):
    m = Mesh(np.array([[0.0, 0], [1, 0], [0, 1]]), np.array([[0, 1, 2]]))
    with pytest.raises(OutputError, match=r"nodir/m\.(node|poly|ele): cannot write") as info:
        write(m, tmp_path / "nodir" / "m.ele")
    assert isinstance(info.value, OSError) and ".tmp-" not in str(info.value)


# the API raises HammeshError subclasses (defect 11) ------------------------------------------


@pytest.fixture(scope="module")
def square_domain():
    return hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])


@pytest.mark.parametrize("call", [
    lambda d: hammesh.quality_mesh(d, timeout=math.inf),
    lambda d: hammesh.quality_mesh(d, timeout=1e300),
    lambda d: hammesh.quality_mesh(d, timeout=float("nan")),
    lambda d: hammesh.quality_mesh(d, min_angle=float("nan")),
    lambda d: hammesh.pointset.hamiltonian_triangulation(np.random.default_rng(0).random((9, 2)), seed=-1),
    lambda d: hammesh.pointset.hamiltonian_triangulation(np.random.default_rng(0).random((9, 2)), seed=1.5),
    lambda d: hammesh.hamiltonian("x"),
    lambda d: hammesh.hamiltonian(hammesh.quality_mesh(d), mode="x"),
    lambda d: hammesh.verify(hammesh.quality_mesh(d)),
    lambda d: hammesh.read_domain(123),
    lambda d: hammesh.read_mesh(123),
    lambda d: hammesh.read_mesh("a.vtu", dim=4),
    lambda d: Mesh(np.zeros((3, 2)), np.array([[0, 1, 2]]), triangle_attributes="abc"),
    lambda d: Mesh("points", np.array([[0, 1, 2]])),
    lambda d: hammesh.hamiltonian(Mesh(np.zeros((3, 2)), np.array([[0.5, 1, 2]]))),
    lambda d: Mesh([[0, 0], [1, 0]], [[0, 1, 2], [0, 1]]),
    lambda d: hammesh.strips.choose_strip(hammesh.quality_mesh(d), restart_index=2**32),
    lambda d: hammesh.strips.choose_strip(hammesh.quality_mesh(d), method="nope"),
])
def test_api_bad_input_raises_a_hammesh_error(square_domain, call):
    with pytest.raises(HammeshError) as info:
        call(square_domain)
    assert "\n" not in str(info.value)


def test_option_messages_list_the_valid_values(square_domain):
    with pytest.raises(InvalidOptionError, match=r"method='nope' is not valid: must be one of 'auto', 'greedy'"):
        hammesh.strips.choose_strip(hammesh.quality_mesh(square_domain), method="nope")


def test_mesh_accepts_lists(square_domain):
    m = Mesh([[0.0, 0], [1, 0], [0, 1]], [[0, 1, 2]], triangle_attributes=[[3.0]])
    assert m.points.dtype == np.float64 and m.triangles.dtype.kind == "i"
    assert m.triangle_attributes.tolist() == [[3.0]]
    h = HamiltonianMesh.from_order(m.points, m.triangles)
    assert h.components.tolist() == [1]


# numba cache (defect 12) -----------------------------------------------------------------


def test_numba_cache_falls_back_with_one_warning(tmp_path, monkeypatch):
    from hammesh import numba_cache

    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    with pytest.warns(RuntimeWarning, match="no writable numba cache directory"):
        fallback = numba_cache.ensure_cache([blocker / "a", blocker / "b"])
    assert fallback is not None and numba_cache.writable_dir(fallback)
    assert os.environ["NUMBA_CACHE_DIR"] == fallback
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    assert numba_cache.ensure_cache([tmp_path / "ok"]) is None


@pytest.mark.slow
def test_import_with_an_unwritable_home_and_cache(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    env = {**os.environ, "HOME": str(blocker / "home"), "XDG_CACHE_HOME": str(blocker / "cache")}
    env.pop("NUMBA_CACHE_DIR", None)
    code = "import hammesh, numpy as np; print(hammesh.pointset.hamiltonian_triangulation(np.random.default_rng(0).random((20, 2)), seed=0).shape)"
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
