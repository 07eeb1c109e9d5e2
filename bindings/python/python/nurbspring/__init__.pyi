"""Type stubs of the nurbspring package (units and shapes in the docstrings of __init__.py)."""

import os
from typing import Any, Dict, List, Optional, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

class InputError(ValueError):
    """Bad input: the message names the file, the key (or argument) and the value."""

class RunError(RuntimeError):
    """A run failed (a solver, a diverged simulation, an output)."""

_ArrayLike = npt.ArrayLike
_PathLike = Union[str, "os.PathLike[str]"]

class Surface:
    @property
    def domain(self) -> Tuple[Tuple[float, float], Tuple[float, float]]: ...
    @overload
    def evaluate(self, u: _ArrayLike, v: _ArrayLike) -> npt.NDArray[np.float64]:
        """Points, shape (N, 3) [m]."""
    @overload
    def evaluate(
        self, u: _ArrayLike, v: _ArrayLike, derivatives: int
    ) -> Union[npt.NDArray[np.float64], Dict[str, npt.NDArray[np.float64]]]:
        """derivatives=1: {"point", "u", "v"}; 2: also {"uu", "uv", "vv"}; each (N, 3)."""

class Curve:
    @property
    def domain(self) -> Tuple[float, float]: ...
    def evaluate(
        self, u: _ArrayLike, derivatives: int = 0
    ) -> Union[npt.NDArray[np.float64], Dict[str, npt.NDArray[np.float64]]]:
        """Points (N, 3) [m]; derivatives=1|2: {"point", "u"[, "uu"]}."""

class Scene:
    @classmethod
    def load(cls, path: _PathLike) -> Scene:
        """Reads a scene file (TOML)."""
    @classmethod
    def from_toml(cls, text: str, name: str = "<string>") -> Scene:
        """Parses scene text; `name` stands for the file in messages."""
    @classmethod
    def from_dict(cls, d: Dict[str, Any], name: str = "<dict>") -> Scene:
        """A scene from a dict of the file's tables."""
    @classmethod
    def paper(cls) -> Scene:
        """The paper's scene (Section IV)."""
    @property
    def path(self) -> str: ...
    @property
    def kind(self) -> str:
        """"surface" or "curve"."""
    @property
    def surface(self) -> Surface: ...
    @property
    def curve(self) -> Curve: ...
    def to_toml(self) -> str: ...

class MassSpring:
    positions: npt.NDArray[np.float64]
    """Node rest positions [m], (N, 3)."""
    masses: npt.NDArray[np.float64]
    """Node masses [kg], (N,)."""
    fixed: npt.NDArray[np.bool_]
    """Fixed nodes, (N,)."""
    springs: npt.NDArray[np.int64]
    """Springs' end nodes, (S, 2)."""
    stiffness: npt.NDArray[np.float64]
    """Spring constants [N/m], (S,)."""
    rest_lengths: npt.NDArray[np.float64]
    """Spring rest lengths [m], (S,)."""
    kinds: List[str]
    elements: List[Dict[str, Any]]
    gravity: npt.NDArray[np.float64]
    grid: Optional[Tuple[int, int]]
    @classmethod
    def from_dict(cls, d: Dict[str, Any], name: str = "<dict>") -> MassSpring:
        """A model from a dict of msm.json's schema."""
    @classmethod
    def load(cls, path: _PathLike) -> MassSpring:
        """Reads an msm.json file."""
    @classmethod
    def from_scene(cls, scene: Scene) -> MassSpring:
        """The MSM of a scene's [msm] section."""
    @property
    def probe_nodes(self) -> npt.NDArray[np.int64]: ...
    @property
    def run_settings(self) -> Dict[str, Any]: ...
    def stability(self) -> Dict[str, float]:
        """omega_max [rad/s], dt_critical [s]."""

class Derivation:
    report: Dict[str, Any]
    """report.json as a dict."""
    msm: Optional[Dict[str, Any]]
    """msm.json as a dict (None for a node reduction)."""
    central_node: Dict[str, npt.NDArray[np.float64]]
    """"t" (T,) [s], "dnurbs" and "msm" (T, 3) [m]."""
    warnings: List[str]
    def mass_spring(self) -> MassSpring: ...

def matrices(scene: Scene) -> Dict[str, Any]:
    """{"M", "D", "K": n × n CSR (SciPy, or (data, indices, indptr, shape)), "f": (n,),
    "dofs": dict, "warnings": list}."""

def modes(scene: Scene, count: int = 6) -> npt.NDArray[np.float64]:
    """Lowest angular frequencies [rad/s], ascending."""

def steady(
    scene: Scene, load_steps: int = 1, linear: bool = False, progress: bool = False
) -> Dict[str, Any]:
    """The equilibrium under the scene's loads (the shell's Newton path at load_steps levels)."""

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
    """{"t": (T,) [s], "probes": (T, P, 3) [m], "energy": {"kinetic", "elastic", "external", "total"}: (T,)
    [J], "integrator", "substeps", "dt", "t_end", "stopped", "warnings"}."""

def derive(
    scene: Scene, derivation: Optional[str] = None, progress: bool = False
) -> Derivation:
    """derivation: "modal", "paper", "excitation" or "reduction"."""

def paper(progress: bool = False) -> Dict[str, Any]:
    """The paper's experiment: report.json of `nurbspring paper` as a dict."""
