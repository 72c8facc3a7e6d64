"""Type stubs of the Rust extension module `dyncontact._dyncontact` (python/src/)."""
from os import PathLike
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str
DEFAULT_SCENE: str
"""The embedded default scene's TOML text (`academic`)."""

class Scene:
    """A dyncontact scene (the README's TOML scene), validated when made; immutable."""

    @staticmethod
    def default() -> Scene:
        """The embedded default scene (`academic`): what `dyncontact run` runs without a scene."""
    @staticmethod
    def from_file(path: Union[str, PathLike[str]]) -> Scene:
        """A scene file (TOML); relative paths in it (a Gmsh mesh) are read from its folder."""
    @staticmethod
    def from_toml(text: str, name: str = "<toml>", dir: Optional[Union[str, PathLike[str]]] = None) -> Scene:
        """A scene from TOML text; `name` names it in messages, relative paths are read from `dir`."""
    @staticmethod
    def from_dict(d: Mapping[str, Any], dir: Optional[Union[str, PathLike[str]]] = None) -> Scene:
        """A scene from a dict of the scene file's tables ({"domain": {...}, ...})."""
    def with_set(self, values: Union[Mapping[str, Any], Sequence[str], str]) -> Scene:
        """A new scene with overrides by the rules of `dyncontact run --set KEY=VALUE`: a dict
        {"contact.compliance": 2000.0, ...} (a str value is the text after `=` as typed) or a
        list of "KEY=VALUE" strings. Raises SceneError (with .key and the CLI's message)."""
    def check(self) -> Dict[str, Any]:
        """Validate and build the problem without solving (`dyncontact check`): a dict with
        `name`, `dimension`, sizes (`nodes`, `triangles`, `tetrahedra`, `velocity_unknowns`,
        `contact_nodes`, ...), `steps`, `step`, the (C.k) limit (`ck_step_limit`,
        `ck_limiting_node`, `ck_note`), `memory_estimate_bytes`, `output_estimate_bytes`, `fits`,
        `lines` and `warnings`."""
    @property
    def name(self) -> str:
        """The scene's name."""
    @property
    def source(self) -> str:
        """Where the scene came from: its file, `<embedded academic scene>`, `<toml>`, `<dict>`."""
    @property
    def overrides(self) -> List[str]:
        """The overrides applied, as `--set KEY=VALUE` arguments in order."""
    def to_toml(self) -> str:
        """The effective scene (overrides applied) as TOML: the scene.toml a run writes."""

class StepRecord:
    """One step of the time loop: its history.csv row and the state after it."""

    step: int
    t: float
    normal_force: float
    """total compressive force on Γ3 (per unit thickness in 2-D)"""
    tangential_force: float
    max_penetration: float
    u: npt.NDArray[np.float64]
    """nodal displacement after the step, shape (nodes, d)"""
    v: npt.NDArray[np.float64]
    """nodal velocity after the step, shape (nodes, d)"""
    @property
    def history(self) -> Dict[str, float]:
        """The step's history.csv row {column: value} (counts as floats)."""
    @property
    def energy(self) -> Dict[str, float]:
        """The (E.1) energy terms after the step and its residual."""

class Steps(Iterator[StepRecord]):
    """The iterator of `Simulation.steps()`."""

    def __iter__(self) -> Steps: ...
    def __next__(self) -> StepRecord: ...

class Simulation:
    """The time loop of a scene, step by step (`for rec in Simulation(scene).steps(): ...`)."""

    def __init__(self, scene: Union[Scene, str, PathLike]) -> None:
        """Build the problem of a Scene or a scene file and its operators (assembly,
        factorization, Delassus operator)."""
    def steps(self) -> Steps:
        """The remaining steps, one StepRecord each; a failed step raises SolverError."""
    def step(self) -> Optional[StepRecord]:
        """Advance one step and return its record (None after the last step)."""
    def initial_record(self) -> StepRecord:
        """The record of t = 0 (history.csv's first row)."""
    @property
    def step_index(self) -> int:
        """The number of steps completed."""
    @property
    def n_steps(self) -> int:
        """The scene's number of steps."""
    @property
    def t(self) -> float:
        """The time of the current state."""
    @property
    def dimension(self) -> int:
        """The space dimension d."""

def history_columns() -> List[str]:
    """The history.csv column names, in order."""

def run_memory(scene: Scene, progress: bool = False) -> Dict[str, Any]:
    """Run writing nothing (`dyncontact.run(scene)` wraps it)."""

def run_folder(
    scene: Scene,
    out: Union[str, PathLike[str]],
    progress: bool = False,
    checkpoint_every: Optional[int] = None,
    resume: bool = False,
    stop_after: Optional[int] = None,
) -> Dict[str, Any]:
    """Run into a run folder, or resume it (`dyncontact.run(scene, out=...)` and
    `dyncontact.resume(out)` wrap it)."""

def run_sweep(
    sweep: Union[str, PathLike[str], Mapping[str, Any]],
    out: Optional[Union[str, PathLike[str]]] = None,
    jobs: Optional[int] = None,
    set: Optional[Mapping[str, Any]] = None,
    plan_only: bool = False,
    oversubscribe: bool = False,
    progress: bool = False,
) -> str:
    """Run a sweep; returns the path of sweep.csv (`dyncontact.sweep` wraps it)."""

def run_refine(
    scene: Scene,
    levels: int = 3,
    ratio: float = 2.0,
    what: str = "both",
    windows: Optional[int] = None,
    out: Optional[Union[str, PathLike[str]]] = None,
    jobs: Optional[int] = None,
    progress: bool = False,
) -> str:
    """Run a refinement study; returns the path of refine.csv (`dyncontact.refine` wraps it)."""

def cli_main(argv: Sequence[str]) -> int:
    """The command line with `argv` (the program's name first): the CLI's exit code
    (`python -m dyncontact` and the `dyncontact` console script call it; not for a running
    session: the CLI's signal handlers stay installed after it returns)."""
