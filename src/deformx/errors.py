"""Exceptions raised by DeformX."""

from __future__ import annotations


class SimulationDiverged(RuntimeError):
    """The simulation produced NaNs or a runaway strain.

    Attributes: ``rod`` (index in the world), ``element`` (element index within that rod),
    ``time`` (s, simulation time of the failing step), ``suggested_dt`` (s).
    """

    def __init__(self, rod: int, element: int, time: float, suggested_dt: float, reason: str,
                 dt: float | None = None) -> None:
        self.rod = rod
        self.element = element
        self.time = time
        self.suggested_dt = suggested_dt
        self.reason = reason
        self.dt = dt
        used = f" with dt = {dt:.3g} s" if dt is not None else ""
        super().__init__(
            f"simulation diverged at t = {time:.6g} s{used}: rod {rod}, element {element}: {reason}. "
            f"Try a time step of dt <= {suggested_dt:.3g} s (or more damping / a softer contact)."
        )
