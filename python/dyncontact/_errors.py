"""The exceptions of dyncontact (raised by the Rust extension, defined here so they are plain
Python classes with attributes)."""
from __future__ import annotations

from typing import Any, Dict, Optional


class SceneError(ValueError):
    """A scene (or sweep, or override) that dyncontact refuses: an unknown key, a wrong type, a
    value out of range, a mesh that cannot be read.

    ``str(e)`` is the command line's message (``dyncontact run`` prints ``error: MESSAGE``);
    ``e.key`` is the key path it names (``"contact.compliance"``), or None when it names none
    (a TOML syntax error, an unreadable file).
    """

    def __init__(self, message: str, key: Optional[str] = None) -> None:
        super().__init__(message)
        self.key = key


class SolverError(RuntimeError):
    """The solver could not continue: a step failed (the contact solver did not converge, the
    (E.1) energy guard tripped, a non-finite value appeared) or a factorization failed.

    ``str(e)`` is the command line's message, with a suggestion; ``e.step`` and ``e.time`` say
    where (None for a factorization that failed before the first step); ``e.residuals`` is a
    dict of what the solver reached: ``kind`` (``solver``, ``non_finite``, ``linear_algebra``)
    and, by cause, ``solver``, ``fixed_point_iteration``, ``iterations``, ``inner_residual`` (a
    contact solve), ``energy_residual_relative``, ``energy_residual_limit`` (the energy guard)
    or ``non_finite_entry``.
    """

    def __init__(
        self,
        message: str,
        step: Optional[int] = None,
        time: Optional[float] = None,
        residuals: Optional[Dict[str, Any]] = None,
    ) -> None:
        super().__init__(message)
        self.step = step
        self.time = time
        self.residuals = dict(residuals or {})
