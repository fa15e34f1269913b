"""numba's event hooks on llvmlite's lock dropped over ``hammesh mesh --workers``'s start
(session 20: ``cluster.quiet_llvm_lock``)."""

from __future__ import annotations

import json
import subprocess
import sys

#: in a fresh process: the hooks numba registers, dropped; kernels still compile,
#: load from the cache and run; a second call finds nothing left to drop; a fork
#: made afterwards runs without them too
_QUIET = """
import json, os
import numba
from llvmlite.binding import ffi
from hammesh.parallel import cluster
before = sum(a.__module__ == "numba.core.base" for a, _ in ffi.lib._lock._cblist)
dropped = cluster.quiet_llvm_lock()
left = sum(a.__module__ == "numba.core.base" for a, _ in ffi.lib._lock._cblist)
again = cluster.quiet_llvm_lock()

@numba.njit(cache=False)
def tri_sum(n):
    s = 0
    for i in range(n):
        s += i * (i + 1) // 2
    return s

from hammesh.predicates import orient_many
import numpy as np
o = orient_many(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.array([[0, 1, 2]], np.int64))
r, w = os.pipe()
pid = os.fork()
if pid == 0:
    os.write(w, str(sum(a.__module__ == "numba.core.base" for a, _ in ffi.lib._lock._cblist)).encode())
    os._exit(0)
os.waitpid(pid, 0)
child = int(os.read(r, 16))
print(json.dumps([before, dropped, left, again, tri_sum(10), int(np.sign(o[0])), child]))
"""


def test_numba_lock_hooks_dropped_and_kernels_still_run():
    out = subprocess.run([sys.executable, "-c", _QUIET], capture_output=True, text=True, timeout=600, check=True)
    before, dropped, left, again, total, sign, child = json.loads(out.stdout.strip().splitlines()[-1])
    assert before >= 1 and dropped == before and left == 0 and again == 0 and child == 0
    assert total == sum(i * (i + 1) // 2 for i in range(10))
    assert sign == 1  # (a counter-clockwise triangle, through a cached kernel loaded after the drop)


def test_not_dropped_in_a_python_callers_process():
    """Importing the parallel path (as a Python caller does) leaves numba's hooks alone."""
    code = ("import numba.core.base; from llvmlite.binding import ffi; import hammesh.parallel.run, "
            "hammesh.parallel.cluster; print(sum(a.__module__ == 'numba.core.base' for a, _ in ffi.lib._lock._cblist))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True)
    assert int(out.stdout.strip()) >= 1
