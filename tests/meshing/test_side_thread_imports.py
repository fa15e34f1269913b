"""quality_mesh's side thread (kernels loaded while the mesher runs in its child) imports
hammesh.postprocess; it must be done importing when quality_mesh returns, or the
caller's next import of the same modules runs beside it and Python hands one thread a
partially initialized module (seen under pytest-xdist: "cannot import name 'KEEP' from
partially initialized module 'hammesh.postprocess.sparse'")."""

from __future__ import annotations

import subprocess
import sys
import textwrap


def test_postprocess_is_fully_imported_when_quality_mesh_returns():
    code = textwrap.dedent("""
        import sys
        import hammesh
        from hammesh.meshing import quality_mesh
        assert "hammesh.postprocess.sparse" not in sys.modules
        quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), max_area=0.05)
        for name in ("hammesh.postprocess", "hammesh.postprocess.sparse"):
            module = sys.modules.get(name)
            assert module is not None, name + " not imported"
            assert not getattr(module.__spec__, "_initializing", False), name + " still initializing"
        print("ok")
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-2000:]
