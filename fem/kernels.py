"""numba kernels of :mod:`probedyn.fem.assembly` (kept in their own module: numba's on-disk
cache is per source file, so editing the drivers does not recompile these).

* :func:`pattern` - node adjacency (block-CSR pattern) and the position of every element block;
* :func:`principal_submatrix` - ``A[keep][:, keep]`` of a CSR matrix (the free-DOF matrices);
* :func:`upper_triangle` - PARDISO's 1-based int32 upper triangle of a symmetric CSR matrix;
* :func:`free_upper_pattern` - the same pattern predicted from the node adjacency (no values);
* :func:`stiffness_kernel` - element stiffness blocks ``sum_q w_q G_q^T C_q G_q`` added in place;
* :func:`mass_kernel` - scalar element masses ``int rho N_a N_b`` added in place;
* :func:`block_to_csr` / :func:`scalar_to_vector_csr` - the interleaved (3N x 3N) CSR arrays of
  a 3 x 3 block matrix / of ``kron(S, I3)`` in one pass (what scipy's ``bsr.tocsr()`` and a
  numpy gather produced, the same arrays);
* :func:`csr_matmat_rows` - rows ``r0:r1`` of ``A @ X`` (CSR times a dense block), releasing
  the GIL so that Python threads can compute disjoint row ranges at once.
"""

from __future__ import annotations

import numpy as np
from numba import njit


# ---------------------------------------------------------------------------------------
# sparsity pattern
# ---------------------------------------------------------------------------------------

@njit(cache=True)
def pattern(ed, n):  # pragma: no cover - compiled
    """Node adjacency of ``ed`` (nel, nb) as CSR (indptr, indices sorted per row) and the
    position ``pos[e, a, b]`` of block (ed[e, a], ed[e, b]) in ``indices``.

    Per row s: its neighbours are inserted in order as they are found (rows are short: 15-60
    nodes for quadratic elements), then every element block of row s is located by a scatter
    array ``loc[t]`` = position of column t in the row (no search, no per-row allocation)."""
    nel, nb = ed.shape
    # node -> (element, local index) incidences
    cnt = np.zeros(n + 1, np.int64)
    for e in range(nel):
        for a in range(nb):
            cnt[ed[e, a] + 1] += 1
    for i in range(n):
        cnt[i + 1] += cnt[i]
    n2e = np.empty(cnt[n], np.int64)
    fill = cnt[:n].copy()
    for e in range(nel):
        for a in range(nb):
            s = ed[e, a]
            n2e[fill[s]] = e * nb + a
            fill[s] += 1
    # row lengths: unique neighbours
    mark = np.full(n, -1, np.int64)
    indptr = np.zeros(n + 1, np.int64)
    for s in range(n):
        c = 0
        for k in range(cnt[s], cnt[s + 1]):
            e = n2e[k] // nb
            for b in range(nb):
                t = ed[e, b]
                if mark[t] != s:
                    mark[t] = s
                    c += 1
        indptr[s + 1] = indptr[s] + c
    indices = np.empty(indptr[n], np.int64)
    pos = np.empty((nel, nb, nb), np.int64)
    loc = np.empty(n, np.int64)
    mark[:] = -1
    for s in range(n):
        lo = indptr[s]
        p = lo
        for k in range(cnt[s], cnt[s + 1]):
            e = n2e[k] // nb
            for b in range(nb):
                t = ed[e, b]
                if mark[t] != s:  # insert t into the sorted row
                    mark[t] = s
                    q = p
                    while q > lo and indices[q - 1] > t:
                        indices[q] = indices[q - 1]
                        q -= 1
                    indices[q] = t
                    p += 1
        for q in range(lo, p):
            loc[indices[q]] = q
        for k in range(cnt[s], cnt[s + 1]):
            e = n2e[k] // nb
            a = n2e[k] - e * nb
            for b in range(nb):
                pos[e, a, b] = loc[ed[e, b]]
    return indptr, indices, pos


@njit(cache=True, nogil=True)
def principal_submatrix(indptr, indices, data, keep, new):  # pragma: no cover - compiled
    """CSR arrays of ``A[keep][:, keep]`` (``new[j]`` = position of column j in ``keep`` or -1);
    one pass over the kept rows, sorted rows stay sorted (``new`` is monotone on ``keep``).  The
    column indices keep the input's integer type (no int64 copy of a 20M-entry int32 array);
    ``nogil``: K's and M's submatrices can be taken at once in two threads."""
    m = keep.size
    ptr = np.zeros(m + 1, np.int64)
    for i in range(m):
        r = keep[i]
        c = 0
        for k in range(indptr[r], indptr[r + 1]):
            if new[indices[k]] >= 0:
                c += 1
        ptr[i + 1] = ptr[i] + c
    ind = np.empty(ptr[m], indices.dtype)
    val = np.empty(ptr[m], data.dtype)
    for i in range(m):
        r = keep[i]
        p = ptr[i]
        for k in range(indptr[r], indptr[r + 1]):
            j = new[indices[k]]
            if j >= 0:
                ind[p] = j
                val[p] = data[k]
                p += 1
    return ptr, ind, val


@njit(cache=True)
def upper_triangle(indptr, indices, data):  # pragma: no cover - compiled
    """PARDISO's input for a symmetric CSR matrix with sorted rows: the upper triangle
    (diagonal included) as 1-based int32 ``ia``, ``ja`` and its values; one pass per row from
    its first entry at or right of the diagonal (scipy's ``triu`` goes through COO and a sort)."""
    n = indptr.size - 1
    start = np.empty(n, np.int64)
    ia = np.empty(n + 1, np.int32)
    ia[0] = 1
    tot = 0
    for i in range(n):
        k = indptr[i]
        hi = indptr[i + 1]
        while k < hi and indices[k] < i:
            k += 1
        start[i] = k
        tot += hi - k
        ia[i + 1] = 1 + tot
    ja = np.empty(tot, np.int32)
    val = np.empty(tot, data.dtype)
    p = 0
    for i in range(n):
        for k in range(start[i], indptr[i + 1]):
            ja[p] = indices[k] + 1
            val[p] = data[k]
            p += 1
    return ia, ja, val


@njit(cache=True)
def free_upper_pattern(indptr, indices, node_new, n_free_nodes):  # pragma: no cover - compiled
    """The pattern PARDISO will see for the free stiffness, from the scalar node adjacency
    (``indptr``, ``indices``, sorted rows) before any value is computed: 1-based int32 ``ia``,
    ``ja`` of the upper triangle of the interleaved 3 x 3 block matrix restricted to the free
    nodes (``node_new[s]`` = free index of node s, or -1; monotone on the free nodes)."""
    old_of = np.empty(n_free_nodes, np.int64)
    for s in range(node_new.size):
        if node_new[s] >= 0:
            old_of[node_new[s]] = s
    n = 3 * n_free_nodes
    ia = np.empty(n + 1, np.int32)
    ia[0] = 1
    tot = 0
    for sn in range(n_free_nodes):
        s = old_of[sn]
        right = 0
        diag = 0
        for k in range(indptr[s], indptr[s + 1]):
            tn = node_new[indices[k]]
            if tn > sn:
                right += 1
            elif tn == sn:
                diag = 1
        for c in range(3):
            tot += 3 * right + diag * (3 - c)
            ia[3 * sn + c + 1] = 1 + tot
    ja = np.empty(tot, np.int32)
    p = 0
    for sn in range(n_free_nodes):
        s = old_of[sn]
        for c in range(3):
            for k in range(indptr[s], indptr[s + 1]):
                tn = node_new[indices[k]]
                if tn == sn:
                    for j in range(3 * sn + c, 3 * sn + 3):
                        ja[p] = j + 1
                        p += 1
                elif tn > sn:
                    for j in range(3 * tn, 3 * tn + 3):
                        ja[p] = j + 1
                        p += 1
    return ia, ja


# ---------------------------------------------------------------------------------------
# element kernels
# ---------------------------------------------------------------------------------------

@njit(cache=True)
def jacobian(X, dNg, q, J):  # pragma: no cover - compiled
    """J[i, j] = dx_i / dxi_j at quadrature point q; returns det J and overwrites J with J^-1."""
    for i in range(3):
        for j in range(3):
            s = 0.0
            for v in range(X.shape[0]):
                s += X[v, i] * dNg[v, j, q]
            J[i, j] = s
    a, b, c = J[0, 0], J[0, 1], J[0, 2]
    d, e, f = J[1, 0], J[1, 1], J[1, 2]
    g, h, k = J[2, 0], J[2, 1], J[2, 2]
    A = e * k - f * h
    B = -(d * k - f * g)
    C = d * h - e * g
    det = a * A + b * B + c * C
    inv = 1.0 / det
    J[0, 0] = A * inv
    J[0, 1] = -(b * k - c * h) * inv
    J[0, 2] = (b * f - c * e) * inv
    J[1, 0] = B * inv
    J[1, 1] = (a * k - c * g) * inv
    J[1, 2] = -(a * f - c * d) * inv
    J[2, 0] = C * inv
    J[2, 1] = -(a * h - b * g) * inv
    J[2, 2] = (a * e - b * d) * inv
    return det


@njit(cache=True)
def stiffness_kernel(Xe, dNg, dN, W, C, pos, out):  # pragma: no cover - compiled
    """Add the element stiffness blocks of elements Xe (ne, nvg, 3) into ``out`` (nnzb, 3, 3).

    ``dNg`` (nvg, 3, nq) reference gradients of the geometry functions, ``dN`` (nb, 3, nq) of
    the scalar element; ``C`` (ne, nqc, 6, 6), nqc = 1 (per element) or nq; ``pos`` (ne, nb, nb).
    Voigt order [11, 22, 33, 23, 13, 12]: the strain of u = phi_a e_c is
    G_a[:, c] with G_a = [[gx,0,0],[0,gy,0],[0,0,gz],[0,gz,gy],[gz,0,gx],[gy,gx,0]].
    """
    ne = Xe.shape[0]
    nb = dN.shape[0]
    nq = W.shape[0]
    nqc = C.shape[1]
    J = np.empty((3, 3))
    g = np.empty((nb, 3))
    D = np.empty((nb, 6, 3))  # C G_b
    Ke = np.empty((nb, nb, 3, 3))
    for e in range(ne):
        Ke[:] = 0.0
        for q in range(nq):
            det = jacobian(Xe[e], dNg, q, J)
            w = W[q] * abs(det)
            for a in range(nb):
                for i in range(3):
                    s = 0.0
                    for j in range(3):
                        s += dN[a, j, q] * J[j, i]
                    g[a, i] = s
            qc = q if nqc > 1 else 0
            Cq = C[e, qc]
            for b in range(nb):
                gx, gy, gz = g[b, 0], g[b, 1], g[b, 2]
                for I in range(6):
                    D[b, I, 0] = w * (Cq[I, 0] * gx + Cq[I, 4] * gz + Cq[I, 5] * gy)
                    D[b, I, 1] = w * (Cq[I, 1] * gy + Cq[I, 3] * gz + Cq[I, 5] * gx)
                    D[b, I, 2] = w * (Cq[I, 2] * gz + Cq[I, 3] * gy + Cq[I, 4] * gx)
            for a in range(nb):
                gx, gy, gz = g[a, 0], g[a, 1], g[a, 2]
                for b in range(a, nb):
                    for k in range(3):
                        Ke[a, b, 0, k] += gx * D[b, 0, k] + gz * D[b, 4, k] + gy * D[b, 5, k]
                        Ke[a, b, 1, k] += gy * D[b, 1, k] + gz * D[b, 3, k] + gx * D[b, 5, k]
                        Ke[a, b, 2, k] += gz * D[b, 2, k] + gy * D[b, 3, k] + gx * D[b, 4, k]
        for a in range(nb):
            for b in range(a, nb):
                p = pos[e, a, b]
                for i in range(3):
                    for k in range(3):
                        out[p, i, k] += Ke[a, b, i, k]
                if b != a:
                    p = pos[e, b, a]
                    for i in range(3):
                        for k in range(3):
                            out[p, i, k] += Ke[a, b, k, i]


@njit(cache=True)
def mass_kernel(Xe, dNg, N, W, rho, pos, out):  # pragma: no cover - compiled
    """Add the scalar element masses ``int rho N_a N_b`` into ``out`` (nnzb,)."""
    ne = Xe.shape[0]
    nb = N.shape[0]
    nq = W.shape[0]
    J = np.empty((3, 3))
    Me = np.empty((nb, nb))
    for e in range(ne):
        Me[:] = 0.0
        for q in range(nq):
            det = jacobian(Xe[e], dNg, q, J)
            w = W[q] * abs(det) * rho[e]
            for a in range(nb):
                wa = w * N[a, q]
                for b in range(a, nb):
                    Me[a, b] += wa * N[b, q]
        for a in range(nb):
            for b in range(a, nb):
                out[pos[e, a, b]] += Me[a, b]
                if b != a:
                    out[pos[e, b, a]] += Me[a, b]



# ---------------------------------------------------------------------------------------
# CSR conversions and products
# ---------------------------------------------------------------------------------------

@njit(cache=True)
def block_to_csr(indptr, indices, blocks, vptr, vind, vdat):  # pragma: no cover - compiled
    """Fill ``vptr``, ``vind``, ``vdat`` (preallocated: 3N + 1, 9 nnzb, 9 nnzb) with the CSR of
    the 3 x 3 block matrix (``indptr``, ``indices``, ``blocks`` (nnzb, 3, 3)): row ``3 s + c``
    holds ``blocks[k, c, d]`` at column ``3 t + d`` for the blocks k = (s, t) of block row s,
    in their order (sorted block rows give sorted rows; every block entry kept, as scipy's
    ``bsr_matrix.tocsr``)."""
    n = indptr.size - 1
    vptr[0] = 0
    for s in range(n):
        lo = indptr[s]
        L = 3 * (indptr[s + 1] - lo)
        for c in range(3):
            base = 9 * lo + c * L
            vptr[3 * s + c + 1] = base + L
            for k in range(lo, indptr[s + 1]):
                q = base + 3 * (k - lo)
                t3 = 3 * indices[k]
                for d in range(3):
                    vind[q + d] = t3 + d
                    vdat[q + d] = blocks[k, c, d]


@njit(cache=True)
def scalar_to_vector_csr(indptr, indices, data, vptr, vind, vdat):  # pragma: no cover - compiled
    """Fill ``vptr``, ``vind``, ``vdat`` (preallocated: 3N + 1, 3 nnz, 3 nnz) with the CSR of
    ``kron(S, I3)`` in the interleaved numbering, only its non-zeros: row ``3 s + c`` holds
    ``S[s, t]`` at column ``3 t + c``."""
    n = indptr.size - 1
    vptr[0] = 0
    for s in range(n):
        lo = indptr[s]
        L = indptr[s + 1] - lo
        for c in range(3):
            base = 3 * lo + c * L
            vptr[3 * s + c + 1] = base + L
            for k in range(lo, indptr[s + 1]):
                vind[base + k - lo] = 3 * indices[k] + c
                vdat[base + k - lo] = data[k]


@njit(cache=True, nogil=True)
def csr_matmat_rows(indptr, indices, data, X, Y, r0, r1):  # pragma: no cover - compiled
    """``Y[r0:r1] = (A @ X)[r0:r1]`` for CSR ``A`` and C-ordered ``X`` (n, k), ``Y`` zeroed.
    Each entry is accumulated over its row's non-zeros in their stored order, as scipy's
    ``csr_matvecs`` does (the same sums, bit for bit).  Compiled with ``nogil``: threads that
    own disjoint row ranges run at once without a numba threading layer."""
    k = X.shape[1]
    for i in range(r0, r1):
        for p in range(indptr[i], indptr[i + 1]):
            a = data[p]
            j = indices[p]
            for c in range(k):
                Y[i, c] += a * X[j, c]


__all__ = ["pattern", "principal_submatrix", "upper_triangle", "free_upper_pattern", "jacobian", "stiffness_kernel", "mass_kernel",
           "block_to_csr", "scalar_to_vector_csr", "csr_matmat_rows"]
