"""Writes the scenes the derivation tests measure (python3 make_scenes.py): flat sheets clamped
by two rings or one ring of control points, a sheet under gravity, a curved rational shell and
a membrane strip; and the kinds the default derivation is judged on besides its refinement
series (docs/derivations.md): a wide sheet under gravity, a graded biquadratic membrane strip,
a rational bending-only bump, an anisotropic membrane under a point load. Control points sit at
the Greville abscissae."""
import math, sys
def clamped(p, n):
    inner = n - p - 1
    return [0.0]*(p+1) + [ (i+1)/(inner+1) for i in range(inner)] + [1.0]*(p+1)
def greville(k, p, n):
    return [sum(k[i+1:i+p+1])/p for i in range(n)]
def graded(p, n, power):
    inner = n - p - 1
    return [0.0]*(p+1) + [((i+1)/(inner+1))**power for i in range(inner)] + [1.0]*(p+1)
def sheet(name, nu, nv, pu, pv, Lx, Ly, mat, rings, vel=(0,0,-0.1), gravity=None, curve=None, weights=None, extra="", ku=None, point=None, dt=0.02):
    ku, kv = ku or clamped(pu, nu), clamped(pv, nv)
    gu, gv = greville(ku, pu, nu), greville(kv, pv, nv)
    rows=[]; wrows=[]
    for i in range(nu):
        row=[]; wr=[]
        for j in range(nv):
            x, y, z = Lx*gu[i], Ly*gv[j], 0.0
            if curve: x, y, z = curve(gu[i], gv[j])
            row.append("[%r, %r, %r]" % (x, y, z))
            wr.append(repr(weights(i,j) if weights else 1.0))
        rows.append("["+", ".join(row)+"]"); wrows.append("["+", ".join(wr)+"]")
    t = ["[surface]", "degree_u = %d" % pu, "degree_v = %d" % pv, "knots_u = %r" % ku, "knots_v = %r" % kv,
         "control_points = [\n  " + ",\n  ".join(rows) + "]"]
    if weights: t.append("weights = [" + ", ".join(wrows) + "]")
    t += ["[material]"] + ["%s = %r" % kv_ for kv_ in mat.items()]
    t += ["[constraints]", "fixed_rings = %d" % rings]
    if gravity or point: t += ["[loads]"]
    if gravity: t += ["gravity = %r" % (list(gravity),)]
    if point: t += ["[[loads.point]]", "u = %r" % point[0], "v = %r" % point[1], "force = %r" % (list(point[2]),)]
    t += ["[initial]", "velocity = %r" % (list(vel),)]
    t += ["[simulation]", "dt = %r" % dt, "t_end = 20.0", "dnurbs_integrator = \"newmark\"", "msm_integrator = \"newmark\""]
    t.append(extra)
    open(name, "w").write("\n".join(t)+"\n")
def main():
    sheet("two_rings.toml", 9, 7, 3, 3, 2.0, 1.5, {"mu": 2.0, "beta11": 0.02, "beta22": 0.03, "beta12": 0.01}, 2)
    sheet("one_ring.toml", 8, 8, 3, 3, 1.0, 1.0, {"mu": 1.0, "alpha11": 0.5, "alpha22": 0.5, "beta11": 0.01, "beta22": 0.01}, 1)
    sheet("gravity.toml", 9, 9, 3, 3, 1.0, 1.0, {"mu": 0.5, "alpha11": 20.0, "alpha22": 15.0, "beta11": 0.05, "beta22": 0.05}, 2, vel=(0,0,0), gravity=(0,0,-9.81))
    R=1.0
    def cyl(u, v):
        a = math.pi/2 * u
        return (R*math.cos(a), 2.0*v, R*math.sin(a))
    # a quarter cylinder with non-uniform weights: a rational shell
    sheet("shell.toml", 8, 7, 3, 3, 1.0, 1.0, {"mu": 1.0, "alpha11": 2.0, "alpha22": 2.0, "beta11": 0.05, "beta22": 0.05, "beta12": 0.02}, 2, vel=(0.05,0,-0.1), curve=cyl, weights=lambda i,j: 1.0 + 0.3*math.sin(math.pi*i/7))
    sheet("strip.toml", 12, 6, 2, 2, 3.0, 1.0, {"mu": 3.0, "alpha11": 1.0, "alpha22": 2.0, "beta11": 0.1}, 1, vel=(0.0,0.0,0.3))
    # The other kinds of the default derivation's judgement (docs/derivations.md), at Δt = 0.01.
    sheet("wide_gravity.toml", 13, 9, 3, 3, 2.0, 1.0, {"mu": 1.0, "alpha11": 1.0, "alpha22": 1.0, "beta11": 0.01, "beta22": 0.01}, 2, vel=(0,0,0), gravity=(0,0,-9.81), dt=0.01)
    sheet("graded_membrane.toml", 14, 6, 2, 2, 3.0, 1.0, {"mu": 3.0, "alpha11": 1.0, "alpha22": 2.0}, 1, vel=(0,0,0.3), ku=graded(2, 14, 1.6), dt=0.01)
    def bump(u, v):
        return (u, v, 0.3*math.sin(math.pi*u)*math.sin(math.pi*v))
    sheet("rational_bump.toml", 10, 10, 3, 3, 1.0, 1.0, {"mu": 1.0, "beta11": 0.02, "beta22": 0.02, "beta12": 0.01}, 2, vel=(0,0,-0.1), curve=bump, weights=lambda i,j: 1.0 + 0.4*math.sin(math.pi*i/9)*math.sin(math.pi*j/9), dt=0.01)
    sheet("aniso_point_load.toml", 11, 11, 3, 3, 1.0, 1.0, {"mu": 1.0, "alpha11": 2.0, "alpha22": 0.5}, 2, vel=(0,0,0), point=(0.4, 0.6, (0, 0, -0.5)), dt=0.01)

if __name__ == "__main__":
    main()
