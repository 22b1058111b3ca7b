# Type stubs of the public API of vibrofem (checked by python/tests/test_stubs.py and, through the
# examples and tests, by mypy --strict in validation/run_live.sh).
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, SupportsIndex, Tuple, Union

import numpy as np
import numpy.typing as npt
import scipy.sparse

from . import _core as _core

__version__: str
__all__: List[str]

#: DOF component names in component order (ux, uy, uz, rx, ry, rz, w).
COMPONENTS: Tuple[str, ...]

_PathArg = Union[str, bytes, "os.PathLike[str]", "os.PathLike[bytes]"]
_FloatArray = npt.NDArray[np.float64]
_IntArray = npt.NDArray[np.int64]
_ComplexArray = npt.NDArray[np.complex128]
_Numbers = Union[float, Sequence[float], npt.NDArray[np.floating[Any]]]
#: A material: "steel" (a name the command line knows) or (E Pa, nu, rho kg/m³).
_MaterialArg = Union[str, Sequence[float]]
#: {group: value} or ["GROUP=VALUE", …] in the command line's grammar.
_GroupValues = Union[Mapping[str, Union[str, _Numbers]], Sequence[str], str, None]

class VibrofemError(Exception): ...
class InputError(VibrofemError): ...
class NumericalError(VibrofemError): ...
class OutputError(VibrofemError): ...
class EngineError(VibrofemError): ...

class Mesh:
    _core: Any
    def __init__(self, core: Any) -> None: ...
    @property
    def source(self) -> str: ...
    @property
    def nodes(self) -> _FloatArray: ...
    @property
    def node_tags(self) -> npt.NDArray[np.uint64]: ...
    @property
    def groups(self) -> Dict[str, Dict[str, int]]: ...
    @property
    def cell_kinds(self) -> Dict[str, int]: ...
    def cells(self, kind: str) -> npt.NDArray[np.uint32]: ...
    def cell_tags(self, kind: str) -> npt.NDArray[np.uint64]: ...
    def group_nodes(self, name: str) -> npt.NDArray[np.uint32]: ...
    def group_cells(self, name: str) -> Dict[str, _IntArray]: ...
    @classmethod
    def from_arrays(
        cls,
        points: npt.ArrayLike,
        cells: Mapping[str, npt.ArrayLike],
        groups: Optional[Mapping[str, Mapping[str, npt.ArrayLike]]] = None,
        source: str = "<arrays>",
    ) -> Mesh: ...
    def to_meshio(self) -> Any: ...
    def to_pyvista(self) -> Any: ...
    def _repr_html_(self) -> str: ...

def read_mesh(source: _PathArg, length_unit: str = "m") -> Mesh: ...
def from_meshio(mesh: Any, length_unit: str = "m") -> Mesh: ...

@dataclass
class Dofs:
    node: _IntArray
    component: _IntArray
    n_mesh_nodes: int
    @property
    def names(self) -> List[str]: ...
    def index(self, node: int, component: Union[int, str]) -> int: ...
    def __len__(self) -> int: ...

@dataclass
class Modes:
    frequencies_hz: _FloatArray
    eigenvalues: _FloatArray
    shapes: _FloatArray
    vectors: _FloatArray
    complete: bool
    accurate: bool
    residuals: _FloatArray
    backward_errors: _FloatArray
    participation: _FloatArray
    effective_mass: _FloatArray
    kinds: List[str]
    report: Dict[str, Any]
    mesh: Optional[Mesh] = None
    @property
    def notes(self) -> List[str]: ...
    def to_meshio(self) -> Any: ...
    def to_pyvista(self) -> Any: ...
    def _repr_html_(self) -> str: ...

@dataclass
class Static:
    displacement: _FloatArray
    von_mises: _FloatArray
    reactions: Dict[str, Dict[str, Tuple[float, float, float]]]
    stiffness: Dict[str, float]
    report: Dict[str, Any]
    mesh: Optional[Mesh] = None
    def to_meshio(self) -> Any: ...
    def to_pyvista(self) -> Any: ...
    def _repr_html_(self) -> str: ...

@dataclass
class Harmonic:
    frequencies_hz: _FloatArray
    displacement: _ComplexArray
    report: Dict[str, Any]
    mesh: Optional[Mesh] = None
    def to_meshio(self) -> Any: ...
    def to_pyvista(self) -> Any: ...
    def _repr_html_(self) -> str: ...

class Model:
    @property
    def mesh(self) -> Mesh: ...
    def __init__(
        self,
        mesh: Union[Mesh, _PathArg, Any],
        material: _MaterialArg = "steel",
        group_material: Union[Mapping[str, _MaterialArg], Sequence[str], None] = None,
        fix: Union[str, Sequence[str], Mapping[str, Union[str, Sequence[str], bool, None]], None] = None,
        couple: Union[str, Sequence[str], Mapping[str, Union[str, _Numbers, bool, None]], None] = None,
        point_mass: _GroupValues = None,
        spring: _GroupValues = None,
        mass: str = "consistent",
        solid: Union[str, Sequence[str], None] = None,
        shell: _GroupValues = None,
        beam: _GroupValues = None,
        hex8: str = "standard",
        length_unit: str = "m",
    ) -> None: ...
    def assemble(self) -> Tuple[scipy.sparse.csr_array, scipy.sparse.csr_array]: ...
    @property
    def dofs(self) -> Dofs: ...
    @property
    def volume(self) -> float: ...
    @property
    def mass(self) -> float: ...
    @property
    def notes(self) -> List[str]: ...
    def modes(
        self,
        n: Optional[SupportsIndex] = None,
        band: Union[Tuple[float, float], Sequence[float], npt.NDArray[np.floating[Any]], None] = None,
        shift_hz: Optional[float] = None,
        block: SupportsIndex = 6,
        engine: str = "native",
        ranks: SupportsIndex = 1,
        prestress: Optional[Mapping[str, Any]] = None,
    ) -> Modes: ...
    def harmonic(
        self,
        force: Union[Mapping[str, Union[Sequence[float], npt.NDArray[np.floating[Any]]]], Sequence[str], str],
        freq: Optional[float] = None,
        sweep: Optional[Tuple[float, float, float]] = None,
        damping: Optional[float] = None,
        rayleigh: Optional[Tuple[float, float]] = None,
        method: str = "modal",
        modes: Optional[SupportsIndex] = None,
        probe: Union[str, Sequence[str], None] = None,
    ) -> Harmonic: ...
    def static(
        self,
        force: _GroupValues = None,
        pressure: _GroupValues = None,
        gravity: Union[_Numbers, str, None] = None,
        displace: Union[
            Mapping[str, Union[Sequence[Optional[float]], npt.NDArray[np.floating[Any]]]], Sequence[str], str, None
        ] = None,
    ) -> Static: ...
    def buckling(
        self,
        force: _GroupValues = None,
        pressure: _GroupValues = None,
        gravity: Union[_Numbers, str, None] = None,
        displace: Union[
            Mapping[str, Union[Sequence[Optional[float]], npt.NDArray[np.floating[Any]]]], Sequence[str], str, None
        ] = None,
        n: SupportsIndex = 4,
    ) -> Any: ...
    def export(self, dir: _PathArg, format: str = "both") -> List[str]: ...

def run_scene(path: _PathArg, out: Optional[_PathArg] = None) -> Dict[str, Any]: ...

@dataclass
class AppReport:
    data: Dict[str, Any]
    out: Path
    html: Path
    markdown: Path
    json: Path
    files: List[Path]
    failure: Optional[str] = None
    passing_variant: Optional[Dict[str, Any]] = None
    def _repr_html_(self) -> str: ...

def design(path: Optional[_PathArg] = None, out: Optional[_PathArg] = None, yes: bool = False) -> AppReport: ...
def crank_drive(path: Optional[_PathArg] = None, out: Optional[_PathArg] = None) -> AppReport: ...
def autobalancer(path: Optional[_PathArg] = None, out: Optional[_PathArg] = None) -> AppReport: ...
def balancer_data(path: Optional[_PathArg] = None, out: Optional[_PathArg] = None) -> AppReport: ...
