"""The leads of docs/derivations.md ("What was tried"), measured on the refinement series of
a flat clamped bicubic sheet (1 × 1, α = 1, β = 0.01, μ = 1, two rings fixed, a uniform initial
velocity; the sheet of crates/scene/tests/support/sheet.rs), by exact modal solutions of both
models over 20 s at Δt = 0.01, the central node against the D-NURBS at its own (u, v), and the
impulse on the free control point nearest (0.3, 0.35):

    python3 scripts/derivation-study/leads.py [7,9,13,17,25,33]

Needs numpy and scipy. Each model is a node-space pair (L, m) on the free Greville nodes,
calibrated so that its lowest frequency is the D-NURBS's (as the derivations do):

- consistent: the linear elements of docs/math.md §8.1 with k = α (springs), β (bends), and
  dual-cell masses μ τ_u τ_v (also uncalibrated);
- reduction, lumped: the exact stiffness K_T = Ω⁻ᵀ S_K Ω⁻¹ with the row sums of M_T;
- control points: S_K itself on the control points (nodes = control points, k_ij = −K_ij) with
  the row sums of S_M;
- approximate dual: L = Sᵀ S_K S, S = I + E/2 (+ 3E²/8), E = I − D⁻¹ S_M, D the row sums (the
  lumped-preconditioned correction of the mass: Sᵀ S_M S = D + O(E²), and Ω S = I + O(h⁴) in the
  interior, so that its node values are the surface's); its stencils reach 3p (4p) nodes.
"""
import sys
import numpy as np
import scipy.linalg as sl
from scipy.interpolate import BSpline


def clamped(p, n):
    inner = n - p - 1
    return np.array([0.0] * (p + 1) + [(i + 1) / (inner + 1) for i in range(inner)] + [1.0] * (p + 1))


def basis(t, p, n, x, d=0):
    out = np.zeros((len(x), n))
    for i in range(n):
        c = np.zeros(n)
        c[i] = 1
        b = BSpline(t, c, p, extrapolate=False)
        out[:, i] = np.nan_to_num((b.derivative(d) if d else b)(np.minimum(x, 1 - 1e-14)))
    return out


def matrices(t, p, n):
    g, w = np.polynomial.legendre.leggauss(p + 2)
    spans = np.unique(t)
    x = np.concatenate([(b - a) / 2 * g + (a + b) / 2 for a, b in zip(spans[:-1], spans[1:])])
    wt = np.concatenate([(b - a) / 2 * w for a, b in zip(spans[:-1], spans[1:])])
    n0, n1, n2 = (basis(t, p, n, x, d) for d in (0, 1, 2))
    return (n0.T * wt) @ n0, (n1.T * wt) @ n1, (n2.T * wt) @ n2


class Sheet:
    def __init__(self, n, p=3, alpha=1.0, beta=0.01, mu=1.0, rings=2):
        t = clamped(p, n)
        self.g = np.array([t[i + 1:i + p + 1].sum() / p for i in range(n)])
        m1, k1, b1 = matrices(t, p, n)
        a1 = alpha * k1 + beta * b1
        sm, sk = mu * np.kron(m1, m1), np.kron(a1, m1) + np.kron(m1, a1)
        fixed = np.zeros((n, n), bool)
        fixed[:rings], fixed[-rings:], fixed[:, :rings], fixed[:, -rings:] = True, True, True, True
        self.free = f = np.where(~fixed.ravel())[0]
        self.n, self.smf = n, sm
        self.K, self.M = sk[np.ix_(f, f)], sm[np.ix_(f, f)]
        self.O = np.kron(basis(t, p, n, self.g), basis(t, p, n, self.g))[np.ix_(f, f)]
        params = np.array([(self.g[i], self.g[j]) for i in range(n) for j in range(n)])[f]
        self.centre = int(np.argmin(((params - 0.5) ** 2).sum(1)))
        self.kick = int(np.argmin(((params - [0.3, 0.35]) ** 2).sum(1)))
        w2, self.Phi = sl.eigh(self.K, self.M)
        self.w = np.sqrt(w2)


def response(K, M, v0, row, t, w=None, phi=None):
    if w is None:
        w2, phi = sl.eigh(K, M)
        w = np.sqrt(np.maximum(w2, 0))
    return ((row @ phi) * (phi.T @ (M @ v0)) / w) @ np.sin(np.outer(w, t))


def judge(s, L, m, calibrate=True):
    m = np.asarray(m, float)
    if calibrate:
        m = m * sl.eigh(L, np.diag(m), eigvals_only=True)[0] / s.w[0] ** 2
    t = np.arange(0, max(20.0, 5 * 2 * np.pi / s.w[0]) + 1e-9, 0.01)
    out = []
    n = len(s.free)
    for v in (np.ones(n), np.eye(n)[s.kick]):
        ref = response(s.K, s.M, v, s.O[s.centre], t, s.w, s.Phi)
        msm = response(L, np.diag(m), s.O @ v, np.eye(n)[s.centre], t)
        out.append(np.sqrt(np.mean((ref - msm) ** 2)) / np.abs(ref).max())
    return out


def consistent(s, alpha=1.0, beta=0.01, mu=1.0):
    x = s.g
    h = np.diff(x)
    tau = np.array([0.5 * ((h[a - 1] if a else 0) + (h[a] if a + 1 < len(x) else 0)) for a in range(len(x))])
    n = s.n
    L = np.zeros((n * n, n * n))
    idx = lambda i, j: i * n + j
    for i in range(n):
        for j in range(n):
            for di, dj, hh, tt in ((1, 0, h, tau), (0, 1, h, tau)):
                a, b = (i, j), (i + di, j + dj)
                if b[0] >= n or b[1] >= n:
                    continue
                w = (tau[j] / h[i]) if di else (tau[i] / h[j])
                c = {idx(*a): 1.0, idx(*b): -1.0}
                for p_, cp in c.items():
                    for q_, cq in c.items():
                        L[p_, q_] += alpha * w * cp * cq
            for di, dj in ((1, 0), (0, 1)):
                k = i if di else j
                if k == 0 or k == n - 1:
                    continue
                h1, h2 = h[k - 1], h[k]
                co = [2 / (h1 * (h1 + h2)), -2 / (h1 * h2), 2 / (h2 * (h1 + h2))]
                nodes = [idx(i - di, j - dj), idx(i, j), idx(i + di, j + dj)]
                for p_, cp in zip(nodes, co):
                    for q_, cq in zip(nodes, co):
                        L[p_, q_] += beta * tau[i] * tau[j] * cp * cq
    f = s.free
    return L[np.ix_(f, f)], (mu * np.outer(tau, tau).ravel())[f]


def main():
    sizes = [int(x) for x in (sys.argv[1] if len(sys.argv) > 1 else "7,9,13,17,25,33").split(",")]
    rows = {}
    for n in sizes:
        s = Sheet(n)
        L, dual = consistent(s)
        Oi = np.linalg.inv(s.O)
        d = s.smf.sum(1)[s.free]
        e = np.eye(len(d)) - s.M / d[:, None]
        s1 = np.eye(len(d)) + 0.5 * e
        s2 = s1 + 0.375 * e @ e
        rows.setdefault("consistent, uncalibrated", []).append(judge(s, L, dual, calibrate=False))
        rows.setdefault("consistent", []).append(judge(s, L, dual))
        rows.setdefault("reduction K_T, lumped M_T", []).append(judge(s, Oi.T @ s.K @ Oi, (Oi.T @ s.M @ Oi).sum(1)))
        rows.setdefault("control points, lumped", []).append(judge(s, s.K, d))
        rows.setdefault("approximate dual, S = I + E/2", []).append(judge(s, s1.T @ s.K @ s1, d))
        rows.setdefault("approximate dual, + 3E²/8", []).append(judge(s, s2.T @ s.K @ s2, d))
    print("| lead | " + " | ".join(f"{n}²" for n in sizes) + " |")
    print("|---|" + "---|" * len(sizes))
    for name, values in rows.items():
        print(f"| {name} | " + " | ".join(f"{100 * a:.1f} / {100 * b:.1f}" for a, b in values) + " |")


if __name__ == "__main__":
    main()
