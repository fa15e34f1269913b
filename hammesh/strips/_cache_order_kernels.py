"""Compiled order of finished strips for a FIFO vertex cache (Tipsy's greedy, per strip).

A cover's strips are fixed here (their triangles, hence their indices); what is chosen is
the order they are sent in and the direction of each.  As in Sander, Nehab and Barczak's
*Tipsy* (2007) and meshoptimizer's ``src/vcacheoptimizer.cpp`` (github.com/zeux/meshoptimizer),
the FIFO is simulated while the order is made; here the unit is a whole strip, so the
indices the cover saved are kept (our code):

* the candidates are the unsent strips through a vertex still in the FIFO (a ring of
  its entries: a vertex is loaded only when it is not cached, so the last ``C`` loads
  are ``C`` distinct vertices, all cached);
* each candidate is simulated in both directions on the FIFO as it is now (an overlay
  of stamps, no copy) and scored by its misses plus ``w_extra`` per index the direction
  costs over the candidate's shorter one (a reversed path may need one more swap),
  both per triangle; the lowest score is sent next;
* with no candidate, the first unsent strip of the cover's own order is sent.
"""

from __future__ import annotations

import numpy as np

from hammesh.strips._numba import kernel, loop_helper

__all__ = ["strips_at_vertices", "fifo_strip_order", "paths_in_order"]


@kernel
def strips_at_vertices(buf, seg_lo, seg_hi, n_vertices):
    """CSR of the strips through each vertex, each once: ``(offsets (n + 1,), strips)``.

    Strip ``s`` is ``buf[seg_lo[s]:seg_hi[s]]`` (its indices, no restart).
    """
    S = seg_lo.shape[0]
    last = np.full(n_vertices, -1, np.int64)
    off = np.zeros(n_vertices + 1, np.int64)
    for s in range(S):
        for i in range(seg_lo[s], seg_hi[s]):
            v = buf[i]
            if last[v] != s:
                last[v] = s
                off[v + 1] += 1
    for v in range(n_vertices):
        off[v + 1] += off[v]
    fill = off[:-1].copy()
    out = np.empty(off[n_vertices], np.int64)
    last[:] = -1
    for s in range(S):
        for i in range(seg_lo[s], seg_hi[s]):
            v = buf[i]
            if last[v] != s:
                last[v] = s
                out[fill[v]] = s
                fill[v] += 1
    return off, out


@loop_helper
def _misses(buf, lo, hi, stamp, now, C, over, over_mark, mark):
    """FIFO misses of ``buf[lo:hi]`` read after the current state, which is left as it is
    (loads of the simulation go to the overlay ``over``, valid where ``over_mark == mark``)."""
    miss = 0
    t = now
    for i in range(lo, hi):
        v = buf[i]
        st = over[v] if over_mark[v] == mark else stamp[v]
        if t - st > C:
            over[v] = t
            over_mark[v] = mark
            t += 1
            miss += 1
    return miss


@kernel
def fifo_strip_order(fw, fw_lo, fw_hi, bw, bw_lo, bw_hi, n_tri, vt_off, vt, n_vertices, C, w_extra):
    """``(pick, flip)``: send strip ``pick[k]`` ``k``-th, reversed where ``flip[k]``.

    ``fw[fw_lo[s]:fw_hi[s]]`` are strip ``s``'s indices as the cover oriented it,
    ``bw[bw_lo[s]:bw_hi[s]]`` reversed; ``n_tri[s]`` its triangles; ``vt_off``/``vt``
    the strips through each vertex (:func:`strips_at_vertices`).
    """
    S = fw_lo.shape[0]
    pick = np.empty(S, np.int64)
    flip = np.zeros(S, np.bool_)
    used = np.zeros(S, np.bool_)
    seen = np.zeros(S, np.int64)
    stamp = np.zeros(n_vertices, np.int64)
    over = np.zeros(n_vertices, np.int64)
    over_mark = np.zeros(n_vertices, np.int64)
    ring = np.full(C, -1, np.int64)
    now = C + 1
    mark = 0
    nxt = 0
    for k in range(S):
        best = -1
        best_flip = False
        best_score = np.inf
        for j in range(C):
            v = ring[j]
            if v < 0:
                continue
            for i in range(vt_off[v], vt_off[v + 1]):
                s = vt[i]
                if used[s] or seen[s] == k + 1:
                    continue
                seen[s] = k + 1
                nf = fw_hi[s] - fw_lo[s]
                nb = bw_hi[s] - bw_lo[s]
                short = min(nf, nb)
                mark += 1
                mf = _misses(fw, fw_lo[s], fw_hi[s], stamp, now, C, over, over_mark, mark)
                sf = (mf + w_extra * (nf - short)) / n_tri[s]
                mark += 1
                mb = _misses(bw, bw_lo[s], bw_hi[s], stamp, now, C, over, over_mark, mark)
                sb = (mb + w_extra * (nb - short)) / n_tri[s]
                if sf < best_score:
                    best_score = sf
                    best = s
                    best_flip = False
                if sb < best_score:
                    best_score = sb
                    best = s
                    best_flip = True
        if best < 0:
            while used[nxt]:
                nxt += 1
            best = nxt
            best_flip = False
        used[best] = True
        pick[k] = best
        flip[k] = best_flip
        buf, lo, hi = (bw, bw_lo[best], bw_hi[best]) if best_flip else (fw, fw_lo[best], fw_hi[best])
        for i in range(lo, hi):
            v = buf[i]
            if now - stamp[v] > C:
                stamp[v] = now
                ring[now % C] = v
                now += 1
    return pick, flip


@kernel
def paths_in_order(order, starts, pick, flip):
    """The paths ``order``/``starts`` sent in the order ``pick``, reversed where ``flip``."""
    S = starts.shape[0] - 1
    out = np.empty(order.shape[0], order.dtype)
    st = np.empty(S + 1, np.int64)
    st[0] = 0
    pos = 0
    for k in range(S):
        s = pick[k]
        a = starts[s]
        b = starts[s + 1]
        if flip[k]:
            for i in range(b - 1, a - 1, -1):
                out[pos] = order[i]
                pos += 1
        else:
            for i in range(a, b):
                out[pos] = order[i]
                pos += 1
        st[k + 1] = pos
    return out, st
