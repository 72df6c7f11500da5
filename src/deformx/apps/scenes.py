"""YAML scene files: validation (pydantic v2), world construction and running.

A scene file describes rods, contact planes, gravity, the time step, the integrator, the
duration and what to write. Every field has a default; unknown fields are rejected, and every
error names the field path (``rods[1].material.youngs_modulus: ...``).

Example (see ``examples/scenes/drape.yaml``)::

    dt: 5.0e-5
    duration: 1.0
    rods:
      - kind: straight
        n_elements: 40
        start: [0, 0, 0.4]
        direction: [1, 0, 0]
        length: 0.8
        material: {radius: 0.005, density: 1200, youngs_modulus: 1.0e6, damping: 1.0}
        pinned: [0]
    planes:
      - {point: [0, 0, 0], normal: [0, 0, 1], static_friction: 0.6}
    output: {directory: out, record_every: 0.02, video: false}
"""

from __future__ import annotations

import math
import re
import time as _time
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import numpy as np
import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    PrivateAttr,
    Tag,
    ValidationError,
    field_validator,
    model_validator,
)

from ..engine.rod import explicit_time_step

__all__ = [
    "Material",
    "StraightRod",
    "PointsRod",
    "Plane",
    "Collider",
    "Output",
    "Attach",
    "JointWave",
    "CoSim",
    "CameraSpec",
    "Scene",
    "SceneResult",
    "load_scene",
    "parse_scene",
    "build_world",
    "run_scene",
    "estimate_stable_dt",
    "warm_up_engine",
]

Vec3 = tuple[float, float, float]
PositiveFloat = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]
NonNegativeFloat = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]
FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
FiniteVec3 = tuple[FiniteFloat, FiniteFloat, FiniteFloat]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_default=True)


def _nonzero(v: Vec3 | None, name: str) -> Vec3 | None:
    if v is not None and math.sqrt(sum(c * c for c in v)) <= 0.0:
        raise ValueError(f"{name} must be a non-zero vector, got {tuple(v)}")
    return v


class Material(_Model):
    """Cross-section and material of a rod (SI units)."""

    radius: PositiveFloat = Field(0.005, description="m")
    density: PositiveFloat = Field(1000.0, description="kg/m^3")
    youngs_modulus: PositiveFloat = Field(1.0e6, description="Pa")
    shear_modulus: PositiveFloat | None = Field(
        None, description="Pa; default E / (2 (1 + poisson_ratio))")
    poisson_ratio: Annotated[float, Field(gt=-1.0, le=0.5)] | None = Field(
        None, description="default 0.5 (incompressible); give this or shear_modulus, not both")
    damping: NonNegativeFloat = Field(0.0, description="1/s, uniform analytical damping")
    internal_damping: NonNegativeFloat = Field(
        0.0, description="s, Kelvin-Voigt retardation time (stable integrator only)")

    @model_validator(mode="after")
    def _one_of_shear(self) -> "Material":
        if self.shear_modulus is not None and self.poisson_ratio is not None:
            raise ValueError("poisson_ratio: give either shear_modulus or poisson_ratio, not both")
        return self


UnitFloat = Annotated[float, Field(ge=0.0, le=1.0)]
Colour = tuple[UnitFloat, UnitFloat, UnitFloat]
ASSETS = ("usb_c_cable", "ethernet_cable", "twisted_pair", "braided_rope")


class Look(_Model):
    """How a rod is drawn in rendered output (``output.render``): a tube with a colour,
    surface and texture, or one of the cable assets skinned to it (straight rods only)."""

    color: Colour | None = Field(None, description="RGB 0-1; default: the palette")
    roughness: UnitFloat = 0.75
    metallic: UnitFloat = 0.0
    texture: str | None = Field(None, description="'stripe', 'bands', 'checker' or an image "
                                "file relative to the scene file")
    texture_color: Colour = (0.95, 0.95, 0.92)
    texture_scale: PositiveFloat = Field(0.05, description="m along the wire per repeat")
    asset: Literal[ASSETS] | None = Field(None, description="a cable model skinned to the rod")


class _RodBase(_Model):
    name: str | None = Field(None, description="label used in plots")
    material: Material = Field(default_factory=Material)
    look: Look | None = Field(None, description="how the rod is drawn (rendered output)")
    fix_start: bool = Field(False, description="clamp position and frame of the first node/element")
    fix_end: bool = Field(False, description="clamp position and frame of the last node/element")
    pinned: list[Annotated[int, Field(ge=0)]] = Field(
        default_factory=list, description="node indices held in place (position only)")

    def n_nodes(self) -> int:  # pragma: no cover - overridden
        raise NotImplementedError

    @model_validator(mode="after")
    def _pinned_in_range(self) -> "_RodBase":
        n = self.n_nodes()
        bad = [i for i in self.pinned if i >= n]
        if bad:
            raise ValueError(f"pinned: node indices must be in [0, {n - 1}], got {bad}")
        return self


class StraightRod(_RodBase):
    """A straight rod from ``start`` along ``direction``."""

    kind: Literal["straight"] = "straight"
    n_elements: Annotated[int, Field(ge=2, le=100_000)] = 50
    start: FiniteVec3 = (0.0, 0.0, 0.5)
    direction: FiniteVec3 = (1.0, 0.0, 0.0)
    length: PositiveFloat = 1.0
    normal: FiniteVec3 | None = Field(None, description="d1 of the first frame, perpendicular to direction")

    @field_validator("direction")
    @classmethod
    def _direction_nonzero(cls, v):
        return _nonzero(v, "direction")

    @field_validator("normal")
    @classmethod
    def _normal_nonzero(cls, v):
        return _nonzero(v, "normal")

    def n_nodes(self) -> int:
        return self.n_elements + 1


class PointsRod(_RodBase):
    """A rod through given node positions (a polyline, optionally closed)."""

    kind: Literal["points"] = "points"
    points: Annotated[list[FiniteVec3], Field(min_length=3)] = Field(
        default_factory=lambda: [(0.0, 0.0, 0.5), (0.5, 0.0, 0.5), (1.0, 0.0, 0.5)],
        description="node positions, m")
    closed: bool = False
    rest_shape: Literal["given", "straight"] = Field(
        "given", description="'given': the points are the stress-free shape; 'straight': a straight rest shape")
    normal: FiniteVec3 | None = Field(None, description="d1 of the first frame")

    @field_validator("normal")
    @classmethod
    def _normal_nonzero(cls, v):
        return _nonzero(v, "normal")

    def n_nodes(self) -> int:
        return len(self.points)


def _rod_kind(v: Any) -> str:
    if isinstance(v, dict):
        return v.get("kind", "straight")
    return getattr(v, "kind", "straight")


RodSpec = Annotated[
    Union[Annotated[StraightRod, Tag("straight")], Annotated[PointsRod, Tag("points")]],
    Discriminator(
        _rod_kind,
        custom_error_type="invalid_rod_kind",
        custom_error_message="must be 'straight' or 'points'",
    ),
]


class Plane(_Model):
    """A one-sided infinite contact plane; rods are kept on the side ``normal`` points to."""

    point: FiniteVec3 = (0.0, 0.0, 0.0)
    normal: FiniteVec3 = (0.0, 0.0, 1.0)
    stiffness: PositiveFloat | None = Field(None, description="N/m per node; default: engine's choice for dt")
    damping: NonNegativeFloat | None = Field(None, description="N s/m per node; default: engine's choice")
    static_friction: NonNegativeFloat = 0.5
    kinetic_friction: NonNegativeFloat | None = Field(None, description="default: static_friction")

    @field_validator("normal")
    @classmethod
    def _normal_nonzero(cls, v):
        return _nonzero(v, "normal")


class Collider(_Model):
    """A mesh or analytic primitive the rods touch (see ``World.add_mesh`` and friends).

    ``kind``: mesh (``path`` to an OBJ/STL/PLY/GLB file, relative to the scene file), sphere
    (``radius``), box (``half_extents``), capsule or cylinder (``radius``, ``length`` along the
    local z axis), blob (a procedural bunny-like closed mesh of about ``radius``, shape from
    ``seed``, lowest point at its origin). ``position`` (m) and ``rotation`` (3x3, world from
    local) place it.
    """

    kind: Literal["mesh", "sphere", "box", "capsule", "cylinder", "blob"]
    seed: Annotated[int, Field(ge=0)] = Field(0, description="shape of a blob")
    path: str | None = Field(None, description="mesh file (kind: mesh)")
    radius: PositiveFloat | None = Field(None, description="m (sphere, capsule, cylinder)")
    length: NonNegativeFloat | None = Field(None, description="m (capsule, cylinder)")
    half_extents: FiniteVec3 | None = Field(None, description="m (box)")
    position: FiniteVec3 = (0.0, 0.0, 0.0)
    rotation: list[FiniteVec3] | None = Field(None, description="3x3 rotation, rows")
    stiffness: PositiveFloat | None = Field(None, description="N/m; default: engine's choice")
    damping: NonNegativeFloat | None = Field(None, description="N s/m; default: critical")
    static_friction: NonNegativeFloat = 0.5
    kinetic_friction: NonNegativeFloat | None = Field(None, description="default: static_friction")

    @model_validator(mode="after")
    def _shape_fields(self):
        need = {"mesh": ("path",), "sphere": ("radius",), "box": ("half_extents",),
                "capsule": ("radius", "length"), "cylinder": ("radius", "length"),
                "blob": ("radius",)}[self.kind]
        for name in need:
            if getattr(self, name) is None:
                raise ValueError(f"a {self.kind} needs '{name}'")
        return self


class Attach(_Model):
    """A rod end held by a MuJoCo body (see ``CoSimulation.attach``)."""

    rod: Annotated[int, Field(ge=0)] = Field(0, description="index into rods")
    end: Union[Literal["start", "end"], int] = "start"
    body: str = Field(..., description="MuJoCo body name")
    offset: FiniteVec3 = Field((0.0, 0.0, 0.0), description="m, in the body's frame")
    frame: bool = True
    coupling: Literal["auto", "kinematic", "inertial"] = "auto"


class JointWave(_Model):
    """A position servo's target: ``mean + amplitude sin(2 pi frequency t + phase)``."""

    actuator: str = Field(..., description="MuJoCo actuator name")
    mean: FiniteFloat | None = Field(None, description="rad or m; default: the start value")
    amplitude: FiniteFloat = 0.0
    frequency: NonNegativeFloat = Field(0.0, description="Hz")
    phase: FiniteFloat = Field(0.0, description="rad")


class CoSim(_Model):
    """Co-simulation with MuJoCo: the bodies of an MJCF file, rods attached to them, bodies
    whose geoms the rods collide with (their reactions go back to the bodies)."""

    mjcf: str = Field(..., description="MJCF file, relative to the scene file")
    keyframe: str | None = Field(None, description="start from this keyframe of the MJCF")
    substeps: Annotated[int, Field(ge=1)] | None = Field(
        None, description="rod steps per MuJoCo step; default: MuJoCo's timestep / dt")
    attach: list[Attach] = Field(default_factory=list)
    colliders: list[str] = Field(default_factory=list,
                                 description="bodies whose geoms become rod colliders "
                                             "('world': the static geoms)")
    controls: list[JointWave] = Field(default_factory=list)


class CameraSpec(_Model):
    """A camera for rendered output (see ``deformx.visual.Camera``); fov_y in degrees."""

    position: FiniteVec3
    look_at: FiniteVec3 = (0.0, 0.0, 0.0)
    up: FiniteVec3 = (0.0, 0.0, 1.0)
    fov_y: Annotated[float, Field(gt=0.0, lt=180.0)] = 45.0
    width: Annotated[int, Field(ge=16, le=4096)] = 640
    height: Annotated[int, Field(ge=16, le=4096)] = 480


class Output(_Model):
    directory: str = Field("deformx-output", description="where files are written")
    name: Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")] = Field(
        "scene", description="file stem: NAME.npz, NAME.png, NAME.mp4")
    record_every: PositiveFloat = Field(0.01, description="s between recorded frames")
    plot: bool = Field(True, description="write a PNG of side and top views")
    video: bool = Field(False, description="write an MP4 (needs imageio-ffmpeg)")
    render: bool = Field(False, description="draw frames with the fast renderer (MuJoCo, "
                                            "shadows): the MP4 and a contact sheet PNG from "
                                            "them, and frames/ with the last frame's RGB, "
                                            "depth, instance masks and camera.json")
    camera: CameraSpec | None = Field(None, description="for render; default: looks at "
                                                        "everything")


class Scene(_Model):
    """A whole scene file."""

    gravity: FiniteVec3 = (0.0, 0.0, -9.81)
    dt: Annotated[float, Field(gt=0.0, le=0.1, allow_inf_nan=False)] = 1.0e-4
    integrator: str = Field("verlet", description="'verlet' (explicit) or 'stable' (large steps)")
    iterations: Annotated[int, Field(ge=1, le=100)] = Field(
        4, description="stable integrator: Newton iterations per step at most")
    tolerance: Annotated[float, Field(gt=0.0, lt=1.0)] = Field(
        1.0e-4, description="stable integrator: converged update / element length")
    duration: Annotated[float, Field(gt=0.0, le=1.0e6, allow_inf_nan=False)] = 1.0
    rods: Annotated[list[RodSpec], Field(min_length=1)] = Field(default_factory=lambda: [StraightRod()])
    planes: list[Plane] = Field(default_factory=list)
    colliders: list[Collider] = Field(default_factory=list)
    rod_contact: bool = Field(True, description="contact between rods and of a rod with itself")
    rod_friction: NonNegativeFloat = Field(0.2, description="Coulomb coefficient of rod contact")
    cosim: CoSim | None = Field(None, description="co-simulate with the bodies of an MJCF file")
    output: Output = Field(default_factory=Output)
    _base_dir: Path | None = PrivateAttr(None)

    @field_validator("integrator")
    @classmethod
    def _integrator_name(cls, v: str) -> str:
        v = v.strip().lower()
        if v not in ("verlet", "stable"):
            raise ValueError(f"must be 'verlet' or 'stable', got {v!r}")
        return v


# --------------------------------------------------------------------------------------------
# loading


def _loc_to_path(loc: tuple) -> str:
    out = ""
    for k, part in enumerate(loc):
        if isinstance(part, int):
            out += f"[{part}]"
        elif k == 2 and loc[0] == "rods" and part in ("straight", "points"):
            # tag of the rod-kind union, not part of the user's field path
            continue
        else:
            out += ("." if out else "") + str(part)
    return out or "(scene)"


_FIELD_PREFIX = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*): (.*)$", re.S)


def format_validation_error(err: ValidationError, source: str = "scene") -> str:
    """One line per error: ``field.path[i].name: message (got value)``."""
    lines = [f"invalid {source}: {err.error_count()} error(s)"]
    for e in err.errors():
        path = _loc_to_path(tuple(e["loc"]))
        msg = e["msg"]
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, "):]
        m = _FIELD_PREFIX.match(msg)
        if m and e["type"] == "value_error":
            # a model-level check that names its field: attach the field to the path
            path = f"{path}.{m.group(1)}" if path != "(scene)" else m.group(1)
            msg = m.group(2)
        if e["type"] == "invalid_rod_kind":
            path += ".kind"
        extra = ""
        if e["type"] == "extra_forbidden":
            msg = "unknown field"
        elif e["type"] != "missing" and "input" in e and not isinstance(e["input"], (dict, list)):
            got = repr(e["input"])
            if got not in msg:
                extra = f" (got {got})"
        lines.append(f"  {path}: {msg}{extra}")
    return "\n".join(lines)


def parse_scene(data: dict | None, source: str = "scene") -> Scene:
    """Validate a scene given as a dict (e.g. parsed YAML). Raises ValueError naming fields."""
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ValueError(f"invalid {source}: the top level must be a mapping of fields, got {type(data).__name__}")
    try:
        return Scene.model_validate(data)
    except ValidationError as err:
        raise ValueError(format_validation_error(err, source)) from None


def load_scene(path: str | Path) -> Scene:
    """Read and validate a YAML scene file. Raises ValueError with readable field paths."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"scene file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as err:
        raise ValueError(f"invalid scene {path}: not valid YAML: {err}") from None
    scene = parse_scene(data, source=f"scene {path}")
    scene._base_dir = path.resolve().parent  # relative mesh paths are relative to the file
    return scene


# --------------------------------------------------------------------------------------------
# building and running


def estimate_stable_dt(length: float, n_elements: int, radius: float, density: float,
                       youngs_modulus: float, shear_modulus: float | None = None,
                       safety: float = 0.3) -> float:
    """A conservative explicit time step (s) for a uniform rod (see ``explicit_time_step``)."""
    G = youngs_modulus / 3.0 if shear_modulus is None else shear_modulus
    return explicit_time_step(length / n_elements, radius, density, youngs_modulus, G, safety)


def _material_kwargs(m: Material) -> dict:
    kw: dict[str, Any] = dict(radius=m.radius, density=m.density, youngs_modulus=m.youngs_modulus,
                              damping=m.damping, internal_damping=m.internal_damping)
    if m.shear_modulus is not None:
        kw["shear_modulus"] = m.shear_modulus
    if m.poisson_ratio is not None:
        kw["poisson_ratio"] = m.poisson_ratio
    return kw


def _rewrap(field: str, err: Exception) -> ValueError:
    return ValueError(f"{field}: {err}")


def build_world(scene: Scene, base_dir: str | Path | None = None):
    """Create the engine world for a validated scene. Returns ``(world, rods)``.

    Engine errors for invalid parameters are re-raised as ValueError prefixed with the scene
    field they came from (``rods[0]: ...``, ``planes[1]: ...``, ``integrator: ...``).
    Relative mesh paths are taken from ``base_dir`` (the scene file's folder).
    """
    base_dir = Path(base_dir) if base_dir is not None else scene._base_dir
    import deformx as dx

    try:
        world = dx.World(gravity=scene.gravity, dt=scene.dt, integrator=scene.integrator,
                         iterations=scene.iterations, tolerance=scene.tolerance,
                         rod_contact=scene.rod_contact, rod_friction=scene.rod_friction)
    except (ValueError, NotImplementedError) as err:
        field = "integrator" if "integrator" in str(err) or isinstance(err, NotImplementedError) else "dt"
        raise _rewrap(field, err) from err

    rods = []
    for i, spec in enumerate(scene.rods):
        where = f"rods[{i}]"
        kw = _material_kwargs(spec.material)
        try:
            if isinstance(spec, StraightRod):
                if spec.normal is not None:
                    kw["normal"] = spec.normal
                rod = dx.Rod.straight(n_elements=spec.n_elements, start=spec.start,
                                      direction=spec.direction, length=spec.length, **kw)
            else:
                if spec.normal is not None:
                    kw["normal"] = spec.normal
                rod = dx.Rod.from_points(np.asarray(spec.points, dtype=float), closed=spec.closed,
                                         rest_shape=spec.rest_shape, **kw)
            world.add_rod(rod)
            if spec.fix_start:
                rod.fix_start()
            if spec.fix_end:
                rod.fix_end()
            for node in spec.pinned:
                rod.pin(node)
        except ValueError as err:
            raise _rewrap(where, err) from err
        rods.append(rod)

    for j, p in enumerate(scene.planes):
        try:
            world.add_plane(point=p.point, normal=p.normal, stiffness=p.stiffness, damping=p.damping,
                            static_friction=p.static_friction, kinetic_friction=p.kinetic_friction)
        except ValueError as err:
            raise _rewrap(f"planes[{j}]", err) from err
    for j, c in enumerate(scene.colliders):
        try:
            _add_collider(world, c, base_dir)
        except ValueError as err:
            raise _rewrap(f"colliders[{j}]", err) from err
    return world, rods


def _add_collider(world, c: Collider, base_dir: Path | None) -> None:
    rotation = np.eye(3) if c.rotation is None else np.asarray(c.rotation, dtype=float)
    pose = (c.position, rotation)
    contact = dict(stiffness=c.stiffness, damping=c.damping, static_friction=c.static_friction,
                   kinetic_friction=c.kinetic_friction)
    if c.kind == "mesh":
        path = Path(c.path)
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        world.add_mesh(str(path), pose=pose, **contact)
    elif c.kind == "sphere":
        world.add_sphere(c.radius, center=c.position, **contact)
    elif c.kind == "box":
        world.add_box(c.half_extents, pose=pose, **contact)
    elif c.kind == "capsule":
        world.add_capsule(c.radius, c.length, pose=pose, **contact)
    elif c.kind == "blob":
        from ..engine.geometry.shapes import blob_mesh

        world.add_mesh(blob_mesh(radius=c.radius, seed=c.seed), pose=pose, **contact)
    else:
        world.add_cylinder(c.radius, c.length, pose=pose, **contact)


def build_cosim(scene: Scene, world, rods, base_dir: str | Path | None = None):
    """The co-simulation of a scene with a ``cosim`` section: ``(sim, drive)``, where
    ``drive(sim)`` sets the servo targets for the coming step (None without controls)."""
    from ..cosim import CoSimulation, MujocoBackend

    c = scene.cosim
    base_dir = Path(base_dir) if base_dir is not None else scene._base_dir
    path = Path(c.mjcf)
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    try:
        backend = MujocoBackend(str(path), keyframe=c.keyframe)
    except ValueError as err:
        raise _rewrap("cosim.mjcf" if "keyframe" not in str(err) else "cosim.keyframe",
                      err) from err
    except Exception as err:  # MuJoCo's own parse errors
        raise ValueError(f"cosim.mjcf: {err}") from err
    try:
        sim = CoSimulation(world, backend, substeps=c.substeps)
    except ValueError as err:
        raise _rewrap("cosim.substeps", err) from err
    for j, body in enumerate(c.colliders):
        try:
            sim.add_colliders(body)
        except ValueError as err:
            raise _rewrap(f"cosim.colliders[{j}]", err) from err
    for j, a in enumerate(c.attach):
        try:
            if a.rod >= len(rods):
                raise ValueError(f"rod: index {a.rod} out of range (the scene has {len(rods)} rods)")
            sim.attach(rods[a.rod], end=a.end, body=a.body, offset=a.offset, frame=a.frame,
                       coupling=a.coupling)
        except ValueError as err:
            raise _rewrap(f"cosim.attach[{j}]", err) from err
    if not c.controls:
        return sim, None
    import mujoco

    m, d = backend.model, backend.data
    waves = []
    for j, w in enumerate(c.controls):
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, w.actuator)
        if k < 0:
            names = [m.actuator(i).name for i in range(m.nu)]
            raise ValueError(f"cosim.controls[{j}].actuator: no actuator {w.actuator!r} "
                             f"(actuators: {', '.join(names)})")
        mean = float(d.ctrl[k]) if w.mean is None else w.mean
        waves.append((k, mean, w.amplitude, 2.0 * math.pi * w.frequency, w.phase))

    def drive(sim) -> None:
        t = sim.time + sim.dt
        for k, mean, amp, omega, phase in waves:
            d.ctrl[k] = mean + amp * math.sin(omega * t + phase)

    return sim, drive


def warm_up_engine(scene: "Scene") -> None:
    """Compile (first run) or load from numba's cache (later runs) the kernels that ``scene``
    uses, by stepping a throwaway copy of its world once, so that timings exclude it."""
    world, rods = build_world(scene)
    if scene.cosim is not None:
        build_cosim(scene, world, rods)[0].step()
    else:
        world.step(1)


class SceneResult(dict):
    """Paths written by :func:`run_scene` (keys ``npz``, ``png``, ``mp4`` when written) plus
    attributes ``wall_time`` (s of simulation), ``compile_time`` (s to compile or load the
    numba kernels), ``render_time`` (s for plot and video), ``n_steps`` and ``sim_time``."""

    wall_time: float = 0.0
    compile_time: float = 0.0
    render_time: float = 0.0
    n_steps: int = 0
    sim_time: float = 0.0


def run_scene(scene: Scene, progress: bool = True, out_dir: str | Path | None = None,
              title: str | None = None) -> SceneResult:
    """Build, run and record a scene; write NAME.npz, NAME.png and (if video) NAME.mp4.

    ``out_dir`` overrides ``scene.output.directory``. Returns a :class:`SceneResult` mapping
    kind -> Path.
    """
    import deformx as dx

    from ..visual import plots

    out = Path(out_dir if out_dir is not None else scene.output.directory)
    out.mkdir(parents=True, exist_ok=True)
    name = scene.output.name

    world, rods = build_world(scene)
    t0 = _time.perf_counter()
    warm_up_engine(scene)
    compile_time = _time.perf_counter() - t0
    recorder = dx.Recorder(world, every=scene.output.record_every)
    sim, drive = (None, None) if scene.cosim is None else build_cosim(scene, world, rods)
    frames = None
    if scene.output.render:
        frames = _frame_recorder(scene, sim if sim is not None else world)
    extra = [frames] if frames is not None else []
    t0 = _time.perf_counter()
    if sim is None:
        world.run(scene.duration, progress=progress, recorder=recorder, callbacks=extra)
    else:
        if drive is not None:
            drive.every = sim.dt  # a callback each macro step: the servo targets
        sim.run(scene.duration, progress=progress,
                callbacks=[recorder] + extra + ([drive] if drive is not None else []))
    wall = _time.perf_counter() - t0
    # Always keep the final state (the recorder samples on its own grid, which the duration
    # need not be a multiple of).
    times = getattr(recorder, "times", None)
    if times is not None and (not times or world.time - times[-1] > 0.5 * world.dt):
        recorder.sample()

    result = SceneResult()
    result.wall_time = wall
    result.compile_time = compile_time
    result.sim_time = float(world.time)
    result.n_steps = int(round(world.time / world.dt))
    npz_path = out / f"{name}.npz"
    saved = recorder.save(npz_path)
    result["npz"] = Path(saved) if saved is not None else npz_path

    t1 = _time.perf_counter()
    if frames is not None:
        if not frames.times or world.time - frames.times[-1] > 0.5 * world.dt:
            frames(world)  # the final state too
        result.update(frames.finish(out, name, video=scene.output.video))
    elif scene.output.plot or scene.output.video:
        with np.load(result["npz"]) as data:
            times = np.asarray(data["time"])
            positions = plots.rods_from_record(data)
        labels = [spec.name or f"rod {i}" for i, spec in enumerate(scene.rods)]
        ground = _ground_z(scene)
        if scene.output.plot:
            result["png"] = plots.plot_snapshots(times, positions, out / f"{name}.png",
                                                 title=title or name, ground_z=ground, labels=labels)
        if scene.output.video:
            result["mp4"] = plots.write_video(times, positions, out / f"{name}.mp4",
                                              title=title or name, ground_z=ground, labels=labels)
    result.render_time = _time.perf_counter() - t1
    return result


def _frame_recorder(scene: Scene, source):
    from ..visual.camera import Camera
    from ..visual.movie import FrameRecorder

    c = scene.output.camera
    camera = None if c is None else Camera(position=c.position, look_at=c.look_at, up=c.up,
                                           fov_y=c.fov_y, width=c.width, height=c.height)
    materials, skins = _looks(scene, source)
    return FrameRecorder(source, camera=camera, every=scene.output.record_every,
                         materials=materials, skins=skins)


def _looks(scene: Scene, source) -> tuple[dict, dict]:
    """Materials and cable-asset skins for the rods whose ``look`` is set (rod index ->)."""
    from ..visual import assets
    from ..visual.fast import PALETTE, world_and_sim
    from ..visual.materials import PROCEDURAL
    from ..visual.materials import Material as Surface

    world, _ = world_and_sim(source)
    materials, skins = {}, {}
    for i, spec in enumerate(scene.rods):
        look = spec.look
        if look is None:
            continue
        where = f"rods[{i}].look"
        color = look.color or PALETTE[i % len(PALETTE)]
        texture = look.texture
        if texture is not None and texture not in PROCEDURAL:
            path = Path(texture)
            if not path.is_absolute() and scene._base_dir is not None:
                path = scene._base_dir / path
            if not path.is_file():
                raise ValueError(f"{where}.texture: no image file {path}")
            texture = str(path)
        materials[i] = Surface(tuple(color), look.roughness, look.metallic, texture,
                               tuple(look.texture_color), look.texture_scale)
        if look.asset is not None:
            rod = world.rods[i]
            if not isinstance(spec, StraightRod):
                raise ValueError(f"{where}.asset: cable assets bind to straight rods")
            radius = float(rod.node_radius[0])
            if look.asset == "twisted_pair":
                asset = assets.twisted_pair(rod.length, radius=radius / 2.0,
                                            colors=(tuple(color), tuple(look.texture_color)))
            else:
                asset = getattr(assets, look.asset)(rod.length, radius=radius,
                                                    color=tuple(color))
            skins[i] = asset.skin(rod)
    return materials, skins


def _ground_z(scene: Scene) -> float | None:
    """Height of the first horizontal plane (normal along +z), for drawing; None if none."""
    for p in scene.planes:
        n = np.asarray(p.normal, dtype=float)
        n = n / np.linalg.norm(n)
        if abs(n[0]) < 1e-9 and abs(n[1]) < 1e-9 and n[2] > 0:
            return float(p.point[2])
    return None
