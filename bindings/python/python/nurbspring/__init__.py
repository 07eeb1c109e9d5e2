"""nurbspring: a NURBS surface with material turned into a mass-spring model.

The scene crate's API with NumPy arrays in and out::

    import nurbspring as ns
    scene = ns.Scene.load("examples/paper.toml")
    mats = ns.matrices(scene)             # M, D, K (SciPy CSR), f, dofs
    omega = ns.modes(scene, count=6)      # rad/s, ascending
    run = ns.simulate(scene, model="dnurbs")
    d = ns.derive(scene, derivation="modal")
    msm = ns.MassSpring.from_dict(d.msm)
    run = ns.simulate(msm, integrator="newmark", dt=0.01, t_end=20.0)

Units are those of the scene (SI in the examples): lengths in m, time in s, angular
frequencies in rad/s, energies in J. Long calls release the GIL and stop on Ctrl-C
(``KeyboardInterrupt``). Bad input raises :class:`InputError` (a ``ValueError``) with the
message the CLI prints (file, key, value); failed runs raise :class:`RunError`.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Optional, Union

import numpy as np

from . import _native
from ._native import InputError, RunError

__all__ = [
    "InputError",
    "RunError",
    "Scene",
    "Surface",
    "Curve",
    "MassSpring",
    "Derivation",
    "matrices",
    "modes",
    "steady",
    "simulate",
    "derive",
    "paper",
]

__version__ = "0.1.0"


def _f64(buffer: bytes, shape: tuple) -> np.ndarray:
    """A writable float64 array of little-endian bytes."""
    return np.frombuffer(buffer, dtype="<f8").astype(np.float64).reshape(shape)


def _i64(buffer: bytes) -> np.ndarray:
    return np.frombuffer(buffer, dtype="<i8").astype(np.int64)


def _as_buffer(x: Any) -> bytes:
    return np.ascontiguousarray(x, dtype="<f8").tobytes()


def _json_default(x: Any) -> Any:
    """NumPy arrays and scalars in dicts given to from_dict."""
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"{type(x).__name__} is not a JSON value")


def _dumps(d: Any, what: str) -> str:
    try:
        return json.dumps(d, default=_json_default, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise InputError(f"{what}: {e}") from None


class Surface:
    """The NURBS surface of a ``[surface]`` scene."""

    def __init__(self, scene: "Scene") -> None:
        self._scene = scene

    @property
    def domain(self) -> tuple:
        """Parameter domain ``((u0, u1), (v0, v1))``."""
        return self._scene._native.domain()

    def evaluate(self, u: Any, v: Any, derivatives: int = 0):
        """Points of the surface at parameters ``(u, v)`` (broadcast against each other).

        With ``derivatives=0`` returns an array of shape ``(N, 3)`` for ``N`` parameter pairs
        (``shape + (3,)`` in general; lengths in m). With ``derivatives=1`` returns a dict with
        ``"point"``, ``"u"`` (∂c/∂u) and ``"v"`` (∂c/∂v); with ``derivatives=2`` also
        ``"uu"``, ``"uv"``, ``"vv"``; each of the same shape. A parameter outside the domain
        raises :class:`InputError`.
        """
        if derivatives not in (0, 1, 2):
            raise InputError(f"derivatives {derivatives}: must be 0, 1 or 2")
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        shape = u.shape
        parts = self._scene._native.evaluate_surface(
            _as_buffer(u.ravel()), _as_buffer(v.ravel()), derivatives
        )
        out = {name: _f64(b, shape + (3,)) for name, b in parts}
        return out["point"] if derivatives == 0 else out


class Curve:
    """The NURBS curve of a ``[curve]`` scene."""

    def __init__(self, scene: "Scene") -> None:
        self._scene = scene

    @property
    def domain(self) -> tuple:
        """Parameter domain ``(u0, u1)``."""
        return self._scene._native.domain()[0]

    def evaluate(self, u: Any, derivatives: int = 0):
        """Points of the curve at parameters ``u``: shape ``(N, 3)`` for ``N`` parameters;
        with ``derivatives=1|2`` a dict with ``"point"``, ``"u"`` (and ``"uu"``)."""
        if derivatives not in (0, 1, 2):
            raise InputError(f"derivatives {derivatives}: must be 0, 1 or 2")
        u = np.asarray(u, dtype=float)
        parts = self._scene._native.evaluate_curve(_as_buffer(u.ravel()), derivatives)
        out = {name: _f64(b, u.shape + (3,)) for name, b in parts}
        return out["point"] if derivatives == 0 else out


class Scene:
    """A scene: geometry, material, loads, constraints, initial state, simulation, lattice and
    fit, read and validated as by the CLI (every key is listed in docs/scenes.md)."""

    def __init__(self, native: "_native.Scene") -> None:
        self._native = native

    @classmethod
    def load(cls, path: Union[str, "os.PathLike[str]"]) -> "Scene":
        """Reads a scene file (TOML). Its path, as given, names the scene in messages and
        reports."""
        return cls(_native.Scene.load(os.fspath(path)))

    @classmethod
    def from_toml(cls, text: str, name: str = "<string>") -> "Scene":
        """Parses scene text; ``name`` stands for the file in messages and reports."""
        return cls(_native.Scene.from_toml(text, name))

    @classmethod
    def from_dict(cls, d: Dict[str, Any], name: str = "<dict>") -> "Scene":
        """A scene from a dict of the file's tables (``{"surface": {...}, "material":
        {...}}``); lists or NumPy arrays for arrays."""
        return cls(_native.Scene.from_json(_dumps(d, name), name))

    @classmethod
    def paper(cls) -> "Scene":
        """The paper's scene (Section IV), as examples/paper.toml."""
        return cls(_native.Scene.paper())

    @property
    def path(self) -> str:
        """The file (or name) the scene came from."""
        return self._native.path

    @property
    def kind(self) -> str:
        """``"surface"`` or ``"curve"``."""
        return self._native.kind

    @property
    def surface(self) -> Surface:
        """The surface of a ``[surface]`` scene (:class:`InputError` for a curve)."""
        if self.kind != "surface":
            raise InputError(f"{self.path}: surface: this scene has a [curve], not a [surface]")
        return Surface(self)

    @property
    def curve(self) -> Curve:
        """The curve of a ``[curve]`` scene (:class:`InputError` for a surface)."""
        if self.kind != "curve":
            raise InputError(f"{self.path}: curve: this scene has a [surface], not a [curve]")
        return Curve(self)

    def to_toml(self) -> str:
        """The scene as TOML text that reads back to an equal scene."""
        return self._native.to_toml()

    def __repr__(self) -> str:
        return f"nurbspring.Scene({self.path!r}, {self.kind})"


def _sparse(parts: tuple):
    nrows, ncols, indptr, indices, data = parts
    triplet = (_f64(data, (-1,)), _i64(indices), _i64(indptr), (nrows, ncols))
    try:
        import scipy.sparse
    except ImportError:
        return triplet
    data, indices, indptr, shape = triplet
    return scipy.sparse.csr_matrix((data, indices, indptr), shape=shape)


def matrices(scene: Scene) -> Dict[str, Any]:
    """The D-NURBS matrices of ``scene`` over all dofs, before constraints are applied.

    Returns ``{"M", "D", "K", "f", "dofs", "warnings"}``: mass ``M`` [kg], damping ``D``
    [kg/s] and stiffness ``K`` [N/m] as ``n × n`` SciPy CSR matrices (``n = dofs_per_point ·
    n_control_points``), or ``(data, indices, indptr, shape)`` CSR triplets without SciPy;
    the load vector ``f`` [N], shape ``(n,)``; ``dofs``, the content of the CLI's dofs.json
    (ordering, fixed and free dofs as int arrays). Every stored entry is the one
    ``nurbspring matrices`` writes, to the last bit.
    """
    raw = _native.matrices(scene._native)
    dofs = json.loads(raw["dofs"])
    dofs.pop("files", None)
    for key in ("fixed_dofs", "free_dofs", "fixed_control_points"):
        dofs[key] = np.asarray(dofs[key], dtype=np.int64)
    return {
        "M": _sparse(raw["M"]),
        "D": _sparse(raw["D"]),
        "K": _sparse(raw["K"]),
        "f": _f64(raw["f"], (-1,)),
        "dofs": dofs,
        "warnings": list(raw["warnings"]),
    }


def modes(scene: Scene, count: int = 6) -> np.ndarray:
    """The lowest ``count`` angular frequencies ω [rad/s] of the constrained D-NURBS,
    ascending, shape ``(min(count, free dofs),)`` (with weights as unknowns: of its
    linearization at the initial shape)."""
    if int(count) < 1:
        raise InputError(f"count {count}: must be at least 1")
    return _f64(_native.modes(scene._native, int(count)), (-1,))


def steady(
    scene: Scene, load_steps: int = 1, linear: bool = False, progress: bool = False
) -> Dict[str, Any]:
    """The D-NURBS at rest under the scene's loads (``nurbspring steady``).

    For a Kirchhoff–Love scene the nonlinear equilibrium is followed by Newton with load
    increments and recorded at ``load_steps`` equal load levels (``linear=True``: the
    linearization at rest instead); a tension plate is one linear solve (its levels scale it).
    Returns ``{"p", "probes", "path", "equations", "iterations", "increments",
    "relative_residual", "warnings"}``: ``p`` the control points at rest, shape
    ``(n_control_points, 3)`` (4 columns, the weight last, with weights as unknowns); ``probes`` as the CLI prints them; ``path`` a list of
    ``{"lambda", "displacements"}`` with the probes' displacements at each level, as
    load_path.csv holds them.
    """
    if int(load_steps) < 1:
        raise InputError(f"load_steps {load_steps}: must be at least 1")
    raw = _native.steady(scene._native, int(load_steps), bool(linear), bool(progress))
    p = _f64(raw["p"], (-1,))
    path = json.loads(raw["path"])
    for level in path:
        level["displacements"] = np.asarray(level["displacements"], dtype=np.float64)
    return {
        "p": p.reshape(-1, raw["dofs_per_point"]),
        "probes": json.loads(raw["probes"]),
        "path": path,
        "equations": raw["equations"],
        "iterations": raw["iterations"],
        "increments": raw["increments"],
        "relative_residual": raw["relative_residual"],
        "warnings": list(raw["warnings"]),
    }


def _run(raw: Dict[str, Any]) -> Dict[str, Any]:
    t = _f64(raw["t"], (-1,))
    kinetic = _f64(raw["kinetic"], (-1,))
    elastic = _f64(raw["elastic"], (-1,))
    external = _f64(raw["external"], (-1,))
    total = _f64(raw["total"], (-1,))
    return {
        "t": t,
        "probes": _f64(raw["probes"], (t.size, raw["n_probes"], 3)),
        "energy": {"kinetic": kinetic, "elastic": elastic, "external": external, "total": total},
        "integrator": raw["integrator"],
        "substeps": raw["substeps"],
        "dt": raw["dt"],
        "t_end": raw["t_end"],
        "stopped": raw["stopped"],
        "halved_steps": raw["halved_steps"],
        "warnings": list(raw["warnings"]),
    }


class MassSpring:
    """A mass-spring model: nodes with masses, springs (and linear elements) between them, with
    its initial state and run settings (msm.json, or a scene's ``[msm]``)."""

    def __init__(self, native: "_native.MassSpring") -> None:
        self._native = native
        f = json.loads(native.to_json())
        nodes = f["nodes"]
        springs = f["springs"]
        #: Node rest positions [m], shape ``(N, 3)``.
        self.positions = np.array([n["position"] for n in nodes], dtype=float).reshape(-1, 3)
        #: Node masses [kg], shape ``(N,)``.
        self.masses = np.array([n["mass"] for n in nodes], dtype=float)
        #: Fixed nodes, shape ``(N,)``, bool.
        self.fixed = np.array([n.get("fixed", False) for n in nodes], dtype=bool)
        #: Springs' end nodes, shape ``(S, 2)``, int.
        self.springs = np.array([[s["a"], s["b"]] for s in springs], dtype=np.int64).reshape(-1, 2)
        #: Spring constants [N/m], shape ``(S,)``.
        self.stiffness = np.array([s["k"] for s in springs], dtype=float)
        #: Spring rest lengths [m], shape ``(S,)``.
        self.rest_lengths = np.array(
            [s.get("rest_length", np.nan) for s in springs], dtype=float
        )
        #: Spring kinds (``"structural"``, ``"shear"``, ``"bend"``), length ``S``.
        self.kinds = [s.get("kind", "structural") for s in springs]
        #: Linear elements: dicts with ``kind``, ``class``, ``nodes`` (int array), ``k``,
        #: ``weight``, ``coefficients`` (empty for a pure spring lattice).
        self.elements = [
            dict(e, nodes=np.asarray(e["nodes"], dtype=np.int64)) for e in f.get("elements", [])
        ]
        #: Gravity [m/s²], shape ``(3,)``.
        self.gravity = np.asarray(f.get("gravity", [0.0, 0.0, 0.0]), dtype=float)
        #: ``(n_u, n_v)`` when the nodes form a grid, else None.
        self.grid = tuple(f["grid"]) if f.get("grid") else None

    @classmethod
    def from_dict(cls, d: Dict[str, Any], name: str = "<dict>") -> "MassSpring":
        """A model from a dict of msm.json's schema (``Derivation.msm``, or your own mesh)."""
        return cls(_native.MassSpring.from_json(_dumps(d, name), name))

    @classmethod
    def load(cls, path: Union[str, "os.PathLike[str]"]) -> "MassSpring":
        """Reads an msm.json file."""
        return cls(_native.MassSpring.load(os.fspath(path)))

    @classmethod
    def from_scene(cls, scene: Scene) -> "MassSpring":
        """The MSM of a scene's ``[msm]`` section, its initial state mapped from the scene's."""
        return cls(_native.MassSpring.from_scene(scene._native))

    @property
    def probe_nodes(self) -> np.ndarray:
        """Watched nodes, the node nearest the centre of the parameter domain first."""
        return np.asarray(self._native.probe_nodes, dtype=np.int64)

    @property
    def run_settings(self) -> Dict[str, Any]:
        """Default ``dt`` [s], ``t_end`` [s] and ``integrator``."""
        dt, t_end, integrator = self._native.run_settings
        return {"dt": dt, "t_end": t_end, "integrator": integrator}

    def stability(self) -> Dict[str, float]:
        """``omega_max`` [rad/s] of the linearized model and the explicit integrators'
        critical step ``dt_critical`` [s]."""
        omega_max, dt_critical = self._native.stability()
        return {"omega_max": omega_max, "dt_critical": dt_critical}

    def __repr__(self) -> str:
        return f"nurbspring.MassSpring({len(self.masses)} nodes, {len(self.stiffness)} springs)"


def simulate(
    target: Union[Scene, MassSpring],
    model: Optional[str] = None,
    *,
    integrator: Optional[str] = None,
    dt: Optional[float] = None,
    t_end: Optional[float] = None,
    force_unstable: bool = False,
    progress: bool = False,
) -> Dict[str, Any]:
    """Simulates a scene's D-NURBS or MSM, or a :class:`MassSpring`.

    ``simulate(scene, model="dnurbs" | "msm", ...)`` (default ``"dnurbs"``) or
    ``simulate(msm, ...)``. ``integrator`` (``"terzopoulos-qin"``, ``"newmark"``, ``"modal"``
    for the D-NURBS; ``"symplectic-euler"``, ``"verlet"``, ``"rk4"``, ``"backward-euler"``,
    ``"newmark"``, ``"modal"`` for an MSM), time step ``dt`` [s] and end time ``t_end`` [s]
    default to the scene's (or file's). ``force_unstable`` runs an explicit integrator above
    its stability limit; ``progress=True`` shows the steps on stderr.

    Returns ``{"t": (T,) [s], "probes": (T, P, 3) [m], "energy": {"kinetic", "elastic",
    "external", "total"}: (T,) each [J] (elastic without the load; external: the load's
    potential; total: their sum), "integrator", "substeps" (steps per ``dt``: more than 1 when
    a scene's explicit integrator runs below its stability limit), "dt", "t_end", "stopped",
    "halved_steps" (steps of an implicit integrator taken in halves after Newton failed on
    them), "warnings"}``; probe 0 is the point (node) at the centre of the parameter domain, then the
    scene's probes.
    These are the samples of the CLI's trajectory.csv and energy.csv.
    """
    options = dict(
        integrator=integrator,
        dt=dt,
        t_end=t_end,
        force_unstable=force_unstable,
        progress=progress,
    )
    if isinstance(target, MassSpring):
        if model not in (None, "msm"):
            raise InputError(f"model {model}: a MassSpring runs as model='msm'")
        return _run(target._native.simulate(**options))
    if isinstance(target, Scene):
        return _run(_native.simulate_scene(target._native, model or "dnurbs", **options))
    raise TypeError(f"simulate() takes a Scene or a MassSpring, not {type(target).__name__}")


class Derivation:
    """A derived MSM and its validation: what ``nurbspring derive`` writes."""

    def __init__(self, raw: Dict[str, Any]) -> None:
        #: report.json, as a dict.
        self.report: Dict[str, Any] = json.loads(raw["report"])
        #: msm.json, as a dict (None for a node reduction).
        self.msm: Optional[Dict[str, Any]] = json.loads(raw["msm"]) if raw["msm"] else None
        t, a, b = raw["central_node"]
        t = _f64(t, (-1,))
        #: The central node over time (central_node.csv): ``"t"`` (T,) [s], ``"dnurbs"`` and
        #: ``"msm"`` (T, 3) [m].
        self.central_node: Dict[str, np.ndarray] = {
            "t": t,
            "dnurbs": _f64(a, (t.size, 3)),
            "msm": _f64(b, (t.size, 3)),
        }
        #: Every sign of a bad model.
        self.warnings = list(raw["warnings"])

    def mass_spring(self) -> MassSpring:
        """The derived model, ready to :func:`simulate`."""
        if self.msm is None:
            raise InputError("this derivation is a node reduction; it has no msm.json")
        return MassSpring.from_dict(self.msm, name=str(self.report.get("scene", "<derived>")))

    def __repr__(self) -> str:
        return f"nurbspring.Derivation({self.report.get('derivation')!r} of {self.report.get('scene')!r})"


def derive(scene: Scene, derivation: Optional[str] = None, progress: bool = False) -> Derivation:
    """Derives the MSM of ``scene``: ``derivation`` is ``"modal"``, ``"paper"``,
    ``"excitation"``, ``"reduction"`` or ``"springs"`` (default: the scene's
    ``fit.derivation``, ``"springs"`` for a shell; a Kirchhoff–Love scene takes ``"springs"``,
    ``"modal"``, ``"excitation"`` or ``"reduction"``). ``.report`` equals the CLI's
    report.json and ``.msm`` its msm.json (a spring model's ``.central_node`` is empty: its
    runs compare every node, see the report). ``progress=True`` shows the paper derivation's
    mass scan on stderr."""
    return Derivation(_native.derive(scene._native, derivation, progress=progress))


def paper(progress: bool = False) -> Dict[str, Any]:
    """The paper's experiment (Section IV) with its built-in scene: the report.json of
    ``nurbspring paper`` as a dict (its ``"paper"`` entry holds the reproduction)."""
    return json.loads(_native.paper(progress=progress)["report"])
