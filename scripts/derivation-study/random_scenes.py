"""Writes 16 random scenes (python3 random_scenes.py OUT_DIR [SEED]) for measuring the
derivations on cases no one tuned for: flat, cylindrical (rational) and saddle sheets, degrees 2
and 3, membrane, bending or mixed materials, one or two fixed rings, excited by an initial
velocity, gravity or both. docs/derivations.md reports the figures for seed 20261201."""
import math, os, random, sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "../../crates/scene/tests/data/derivations"))
from make_scenes import sheet


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 20261201
    os.makedirs(out, exist_ok=True)
    rnd = random.Random(seed)
    for k in range(16):
        nu, nv = rnd.randint(6, 12), rnd.randint(6, 11)
        pu, pv = rnd.choice([2, 3, 3]), rnd.choice([2, 3, 3])
        lx, ly = rnd.uniform(0.5, 3), rnd.uniform(0.5, 2)
        kind = rnd.choice(["membrane", "bending", "mixed"])
        mat = {"mu": round(rnd.uniform(0.2, 3), 3)}
        if kind != "bending":
            mat["alpha11"] = round(rnd.uniform(0.2, 20), 3)
            mat["alpha22"] = round(mat["alpha11"] * rnd.uniform(0.5, 1.5), 3)
        if kind != "membrane":
            mat["beta11"] = round(rnd.uniform(0.005, 0.1), 4)
            mat["beta22"] = round(mat["beta11"] * rnd.uniform(0.5, 1.5), 4)
            if rnd.random() < 0.5:
                mat["beta12"] = round(mat["beta11"] * rnd.uniform(0.1, 0.6), 4)
        # A bending-only sheet held by one ring is a mechanism at its corners: two rings.
        rings = rnd.choice([1, 2]) if kind != "bending" else 2
        exc = rnd.choice(["vel", "grav", "both", "vel"])
        vel = (0, 0, -round(rnd.uniform(0.05, 0.5), 3)) if exc != "grav" else (0, 0, 0)
        grav = (0, 0, -9.81) if exc != "vel" else None
        shape = rnd.choice(["flat", "flat", "cyl", "saddle"])
        curve, weights = None, None
        if shape == "cyl":
            r = rnd.uniform(0.8, 2.0)
            curve = lambda u, v, r=r, lx=lx, ly=ly: (r * math.cos(lx / r * u), ly * v, r * math.sin(lx / r * u))
            weights = lambda i, j, nu=nu: 1.0 + 0.2 * math.sin(math.pi * i / (nu - 1))
        elif shape == "saddle":
            c = rnd.uniform(0.1, 0.4)
            curve = lambda u, v, c=c, lx=lx, ly=ly: (lx * u, ly * v, c * ((u - 0.5) ** 2 - (v - 0.5) ** 2))
        name = os.path.join(out, "r%02d.toml" % k)
        sheet(name, nu, nv, pu, pv, lx, ly, mat, rings, vel=vel, gravity=grav, curve=curve, weights=weights)
        print(name, nu, nv, pu, pv, kind, rings, exc, shape)


if __name__ == "__main__":
    main()
