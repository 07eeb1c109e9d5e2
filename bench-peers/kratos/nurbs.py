"""Minimal NURBS utilities (numpy) used to build the exact control nets.

Nets are stored in homogeneous form Pw[i, j, :] = (w*x, w*y, w*z, w), with i along u
and j along v.  Only what is needed here: Bezier degree elevation of a single-segment
patch, Boehm knot insertion, and rational basis evaluation.
"""
from math import comb
import numpy as np


def bezier_elevate_1d(Pw, t):
    """Degree elevate a single Bezier segment (axis 0 of Pw) by t."""
    p = Pw.shape[0] - 1
    q = p + t
    out = np.zeros((q + 1,) + Pw.shape[1:])
    for i in range(q + 1):
        for j in range(max(0, i - t), min(p, i) + 1):
            out[i] += comb(p, j) * comb(t, i - j) / comb(q, i) * Pw[j]
    return out


def insert_knot_1d(Pw, knots, p, ubar):
    """Boehm insertion of one knot ubar (multiplicity 1) along axis 0 of Pw."""
    knots = list(knots)
    n = Pw.shape[0]
    # span k with knots[k] <= ubar < knots[k+1]
    k = max(i for i in range(len(knots) - 1) if knots[i] <= ubar < knots[i + 1])
    Q = np.zeros((n + 1,) + Pw.shape[1:])
    for i in range(n + 1):
        if i <= k - p:
            Q[i] = Pw[i]
        elif i >= k + 1:
            Q[i] = Pw[i - 1]
        else:
            a = (ubar - knots[i]) / (knots[i + p] - knots[i])
            Q[i] = a * Pw[i] + (1.0 - a) * Pw[i - 1]
    new_knots = knots[:k + 1] + [ubar] + knots[k + 1:]
    return Q, new_knots


class Surface:
    """Tensor-product NURBS surface in homogeneous form."""

    def __init__(self, Pw, p, q, U, V):
        self.Pw = np.array(Pw, dtype=float)
        self.p, self.q = p, q
        self.U, self.V = [float(x) for x in U], [float(x) for x in V]
        assert len(self.U) == self.Pw.shape[0] + p + 1
        assert len(self.V) == self.Pw.shape[1] + q + 1

    @classmethod
    def from_cartesian(cls, P, W, p, q, U, V):
        P = np.asarray(P, float)
        W = np.asarray(W, float)
        Pw = np.concatenate([P * W[..., None], W[..., None]], axis=-1)
        return cls(Pw, p, q, U, V)

    @property
    def points(self):
        return self.Pw[..., :3] / self.Pw[..., 3:4]

    @property
    def weights(self):
        return self.Pw[..., 3]

    def elevate_bezier(self, pu, qv):
        """Elevate a single-element (Bezier) patch to degrees (pu, qv)."""
        assert len(self.U) == 2 * (self.p + 1) and len(self.V) == 2 * (self.q + 1)
        Pw = bezier_elevate_1d(self.Pw, pu - self.p)
        Pw = np.swapaxes(bezier_elevate_1d(np.swapaxes(Pw, 0, 1), qv - self.q), 0, 1)
        U = [0.0] * (pu + 1) + [1.0] * (pu + 1)
        V = [0.0] * (qv + 1) + [1.0] * (qv + 1)
        return Surface(Pw, pu, qv, U, V)

    def insert_u(self, knots):
        Pw, U = self.Pw, self.U
        for k in knots:
            Pw, U = insert_knot_1d(Pw, U, self.p, float(k))
        return Surface(Pw, self.p, self.q, U, self.V)

    def insert_v(self, knots):
        Pw, V = np.swapaxes(self.Pw, 0, 1), self.V
        for k in knots:
            Pw, V = insert_knot_1d(Pw, V, self.q, float(k))
        return Surface(np.swapaxes(Pw, 0, 1), self.p, self.q, self.U, V)

    # ---- evaluation -------------------------------------------------------
    @staticmethod
    def bspline_basis(knots, p, n, x):
        """All n B-spline basis values at x (Cox-de Boor, right end closed)."""
        knots = np.asarray(knots)
        N = np.zeros(len(knots) - 1)
        if x >= knots[-1]:
            k = max(i for i in range(len(knots) - 1) if knots[i] < knots[i + 1])
        else:
            k = max(i for i in range(len(knots) - 1) if knots[i] <= x < knots[i + 1])
        N[k] = 1.0
        for d in range(1, p + 1):
            Nn = np.zeros(len(knots) - 1 - d)
            for i in range(len(Nn)):
                v = 0.0
                if knots[i + d] > knots[i]:
                    v += (x - knots[i]) / (knots[i + d] - knots[i]) * N[i]
                if knots[i + d + 1] > knots[i + 1]:
                    v += (knots[i + d + 1] - x) / (knots[i + d + 1] - knots[i + 1]) * N[i + 1]
                Nn[i] = v
            N = Nn
        return N[:n]

    def rational_basis(self, u, v):
        nu, nv = self.Pw.shape[:2]
        Nu = self.bspline_basis(self.U, self.p, nu, u)
        Nv = self.bspline_basis(self.V, self.q, nv, v)
        R = np.outer(Nu, Nv) * self.weights
        return R / R.sum()

    def point(self, u, v):
        R = self.rational_basis(u, v)
        return np.einsum('ij,ijk->k', R, self.points)
