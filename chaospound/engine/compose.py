"""Compose, don't dispatch: one generated engine module per composition.

A :class:`Composition` names each varying piece once, in Python: the structural
model, the contact law, the ground motion, the Runge-Kutta method and whether
tangent vectors ride along. :func:`engine_for` turns it into a module whose
kernels call exactly those pieces, so no kernel ever branches on a kind of
thing, and LLVM inlines the law and the ground into the right-hand side as if
they had been written there:

* the **text** is the template modules (:data:`TEMPLATES`: the model, the glue,
  the steppers, the events and the loop), each cut at its ``# ==== template
  ====`` line, joined with bindings of the names they leave free
  (:mod:`chaospound.kernels.free`): ``law_*`` imported from the law's module, ``ground_*`` from
  the ground motion's, the method's stepper, dense output, error and
  controller, and the composition's constants (state size, contact ends,
  block offsets);
* the **file** is ``<cache>/composed/engine_<key>.py``; the key hashes the
  text's sources (every module of the kernel packages), numba's and Python's
  versions and the composition, so an edit anywhere yields a new module and
  nothing is ever invalidated by hand; it is written atomically (a private
  temporary file, fsync, ``os.replace``), so concurrent first runs (sweep
  workers, Dask) are safe;
* its loop ``run`` is ``cache=True``: numba's disk cache serves the second process
  (docs/design/composition.md measured this variant: the same machine code as
  direct calls, and cache hits); the kernels linked into the loop are compiled
  for kernels only, without a CPython wrapper, a cache entry or machine code of
  their own (:class:`chaospound.kernels.jit.InternalDispatcher`);
* processes that start on one composition together (sweep workers, Dask,
  pytest-xdist) take turns: the first compiles the loop under a lock beside the
  module's file, the others load what it cached (:meth:`Engine._load_loop`).

A user system (:func:`chaospound.dynamics.system.custom_system`) is composed the
same way, its functions imported from their own module by name; functions that
cannot be imported (defined in ``__main__``, a notebook, a closure) are bound
into a module built in memory instead, compiled once per process.
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import importlib
import os
import sys
import threading
import types
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: concurrent first runs compile twice
    fcntl = None

from ..kernels.params import N_PARAMS, P_BETA, P_PERIOD_RATIO
from ..solvers.tableaux import MAX_DENSE, MAX_STAGES, METHODS
from .tables import MAX_EVENTS, N_SCALARS

__all__ = ["Composition", "Engine", "UserFunctions", "cache_root", "engine_for",
           "generate_source"]

TEMPLATE_VERSION = "1"  #: part of every key: bump when the generator's output changes
MARKER = "# ==== template ====\n"  #: where a template module's text starts

#: the structural models: name -> template module (one registration line each)
MODELS = {
    "wall": "chaospound.physics.models.wall",
    "tower-wall": "chaospound.physics.models.tower_wall",
    "pair": "chaospound.physics.models.pair",
    "towers": "chaospound.physics.models.towers",
    "lorenz": "chaospound.physics.models.lorenz",
    "duffing": "chaospound.physics.models.duffing",
    "user": "chaospound.physics.models.user",
}
POINT_MODELS = ("wall", "pair")  #: the models with a point contact (the others: a line)
#: the contact laws: name -> module (one registration line each)
LAWS = {
    "hertz": "chaospound.physics.contact.hertz",
    "linear": "chaospound.physics.contact.linear",
    "kelvin-voigt": "chaospound.physics.contact.kelvin_voigt",
    "hertzdamp": "chaospound.physics.contact.hertzdamp",
    "hunt-crossley": "chaospound.physics.contact.hunt_crossley",
    "jankowski": "chaospound.physics.contact.jankowski",
}
#: the ground motions: name -> module (one registration line each)
GROUNDS = {
    "sine": "chaospound.physics.ground.sine",
    "none": "chaospound.physics.ground.none",
    "record": "chaospound.physics.ground.record",
    "stochastic": "chaospound.physics.ground.stochastic",
}
#: the engine's own templates, after the model's
TEMPLATES = ("chaospound.engine.glue", "chaospound.solvers.steppers",
             "chaospound.engine.events", "chaospound.engine.memory", "chaospound.engine.loop")
LAW_FUNCTIONS = ("point_force", "point_stiffness", "point_force_rate", "point_potential",
                 "line_force", "line_gradient", "line_force_rate", "line_potential", "on_onset")
#: the memory kernels of a law with MEMORY (a law without: chaospound.physics.contact.memoryless)
MEMORY_FUNCTIONS = ("onset_sensitivity", "point_memory_force", "line_memory_force")
#: what a model defines to carry a law's memory in its tangent dynamics (a model
#: without them: chaospound.physics.models.no_memory, and check_tangent refuses)
MODEL_MEMORY_FUNCTIONS = ("model_memory_linearize", "model_memory_jvp", "model_onset_variation",
                          "model_onset_accel")
GROUND_FUNCTIONS = ("at", "at_y", "anchor", "shifted", "at_anchor", "next_kink",
                    "acceleration")
#: the models with a Y degree of freedom, the only ones a ground's y component drives
Y_MODELS = ("towers", "tower-wall")
TANGENTS = ("none", "qr", "propagator")  #: what may ride along the state
_PACKAGE = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class UserFunctions:
    """A user system's functions, as the composition binds them.

    ``module`` and the names locate them for an import by name (``module`` is
    None when they cannot be imported); ``digest`` is the sha256 of the
    module's file, part of the key.
    """

    rhs: object
    jacobian: object
    gap: object | None
    n: int
    module: str | None
    names: tuple[str, str, str | None]
    digest: str

    @classmethod
    def of(cls, rhs, jacobian, gap, n: int) -> UserFunctions:
        names = (_name(rhs), _name(jacobian), _name(gap) if gap is not None else None)
        module = _importable_module(rhs, jacobian, gap)
        digest = ""
        if module is not None:
            digest = hashlib.sha256(Path(sys.modules[module].__file__).read_bytes()).hexdigest()
        return cls(rhs, jacobian, gap, n, module, names, digest)

    def canonical(self) -> str:
        where = self.module if self.module is not None else f"memory:{id(self.rhs):x}"
        return f"{where}:{self.names}:{self.digest}:n={self.n}"


@dataclass(frozen=True)
class Composition:
    """What an engine integrates, each piece named once.

    Attributes
    ----------
    model : str
        A key of :data:`MODELS`.
    law : str
        A key of :data:`LAWS` (ignored by models without contact).
    ground : str
        A key of :data:`GROUNDS`.
    method : str
        A key of :data:`chaospound.solvers.tableaux.METHODS`.
    tangent : str
        What rides along the state: "none"; "qr", tangent vectors of the
        variational equations re-orthonormalised at every section (Lyapunov
        exponents); "propagator", the same vectors stored and reset to the
        identity at every section (the per-section propagators whose product is
        a monodromy matrix: periodic orbits and their Floquet multipliers).
    user : UserFunctions or None
        A user system's functions (model "user").
    ground_y : bool
        The ground's y component drives the towers' Y equations (a model of
        :data:`Y_MODELS`, a ground other than "none"): bound as the constant
        ``GROUND_Y``, so a composition without it compiles the x-only equations
        and pays nothing (docs/ground_motions.md section 2).
    """

    model: str
    law: str = "hertz"
    ground: str = "sine"
    method: str = "dopri5"
    tangent: str = "none"
    user: UserFunctions | None = None
    ground_y: bool = False

    def __post_init__(self) -> None:
        for label, value, known in (("model", self.model, MODELS), ("law", self.law, LAWS),
                                    ("ground", self.ground, GROUNDS),
                                    ("method", self.method, METHODS)):
            if value not in known:
                raise ValueError(f"{label} = {value!r}: need one of {', '.join(known)}")
        if self.tangent not in TANGENTS:
            raise ValueError(f"tangent = {self.tangent!r}: need one of {', '.join(TANGENTS)}")
        if (self.model == "user") != (self.user is not None):
            raise ValueError("a user model needs its functions, and only a user model has them")
        if self.ground_y and self.model not in Y_MODELS:
            raise ValueError(f"ground_y on the {self.model} model: only {', '.join(Y_MODELS)} "
                             "have a Y degree of freedom for a y ground motion to drive")
        if self.ground_y and self.ground == "none":
            raise ValueError("ground_y with ground 'none': there is no y component")

    def canonical(self) -> str:
        """The composition as text (part of the key)."""
        text = (f"model={self.model};law={self.law};ground={self.ground};"
                f"method={self.method};tangent={self.tangent}")
        if self.ground_y:
            text += ";ground_y"
        if self.user is not None:
            text += f";user={self.user.canonical()}"
        return text

    def with_tangent(self, tangent: str = "qr") -> Composition:
        return Composition(self.model, self.law, self.ground, self.method, tangent, self.user,
                           self.ground_y)

    def compiled(self) -> Composition:
        """The composition whose engine module runs this one: the "qr" module runs
        all three tangents. "qr" and "propagator" integrate the same tangent vectors
        and differ only in what the loop records at a section (its ``propagate``
        argument, like the other output choices); a state without vectors ("none")
        skips them at run time (the loop's ``n_vectors`` is 0, and the right-hand side
        tests the state's length), the same arithmetic as a module without them.
        One module per composition is one compile per process where a run and its
        exponents or orbit follow each other (a sweep point, classify, a test file).
        A composition whose tangent dynamics :func:`check_tangent` refuses keeps its
        own "none" module."""
        if self.tangent == "none":
            try:
                check_tangent(self.with_tangent("qr"))
            except ValueError:
                return self
        return self if self.tangent == "qr" else self.with_tangent("qr")

    def label(self) -> str:
        """Short human label: ``towers/hertz/sine/dopri5`` (``sine+y`` with ground_y)."""
        parts = [self.model, self.law, self.ground + ("+y" if self.ground_y else ""),
                 self.method]
        if self.tangent != "none":
            parts.append(self.tangent)
        return "/".join(parts)


# ---------------------------------------------------------------- generation


def _template_text(module: str) -> tuple[str, str]:
    """``(prefix, body)`` of a template module: its set-up (imports, constants;
    without its docstring, the :mod:`chaospound.kernels.free` import and the decorators' import,
    which the generated module binds) and its template text."""
    path = _module_path(module)
    source = path.read_text()
    if MARKER not in source:
        raise RuntimeError(f"{path} is not a template: no {MARKER.strip()!r} line")
    prefix, body = source.split(MARKER, 1)
    tree = ast.parse(prefix)
    lines = prefix.splitlines(keepends=True)
    drop: set[int] = set()
    for node in tree.body:
        is_doc = (isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
                  and isinstance(node.value.value, str))
        is_bound = isinstance(node, ast.ImportFrom) and node.module in (
            "chaospound.kernels.free", "chaospound.kernels.jit")
        if is_doc or is_bound:
            drop.update(range(node.lineno - 1, node.end_lineno))
    kept = "".join(line for i, line in enumerate(lines) if i not in drop)
    return kept.strip() + "\n", body.strip() + "\n"


def _module_path(module: str) -> Path:
    parts = module.split(".")
    if parts[0] != "chaospound":
        raise ValueError(f"{module}: templates live in the chaospound package")
    return _PACKAGE.joinpath(*parts[1:]).with_suffix(".py")


def _bindings(c: Composition) -> str:
    """The header that binds every free name of the templates for ``c``."""
    method = METHODS[c.method]
    law = LAWS[c.law]
    ground = GROUNDS[c.ground]
    lines = [
        "# ---- the composition's bindings",
        "from chaospound.solvers.controllers import " + f"{method.controller} as controller",
    ]
    if method.error:
        lines.append(f"from chaospound.solvers.errors import {method.error} as step_error")
    if method.tableau:
        t = method.tableau
        lines.append(f"from chaospound.solvers.tableaux import {t}_A as TAB_A, {t}_B as TAB_B, "
                     f"{t}_C as TAB_C")
    lines.append(f"from {law} import " + ", ".join(f"{f} as law_{f}" for f in LAW_FUNCTIONS))
    lines.append(f"from {ground} import "
                 + ", ".join(f"{f} as ground_{f}" for f in GROUND_FUNCTIONS))
    law_module = importlib.import_module(law)
    memory = law if law_module.MEMORY else "chaospound.physics.contact.memoryless"
    lines.append(f"from {memory} import "
                 + ", ".join(f"{f} as law_{f}" for f in MEMORY_FUNCTIONS))
    jumps = law if law_module.JUMPS else "chaospound.physics.contact.memoryless"
    shifts = bool(getattr(law_module, "SHIFTED_TANGENT", False))
    switches = law if law_module.JUMPS or shifts else "chaospound.physics.contact.memoryless"
    lines.append(f"from {jumps} import on_sides as law_on_sides, point_jump as law_point_jump")
    lines.append(f"from {switches} import point_switch as law_point_switch, "
                 "on_switch as law_on_switch")
    shifted = law if shifts else "chaospound.physics.contact.memoryless"
    lines.append(f"from {shifted} import point_shift as law_point_shift, "
                 "shift_scale as law_shift_scale")
    if not model_carries_memory(c.model):
        lines.append("from chaospound.physics.models.no_memory import "
                     + ", ".join(MODEL_MEMORY_FUNCTIONS))
    lines += [
        f"LAW = {law_base(c.law)}",
        f"LAW_DISSIPATIVE = {bool(law_module.DISSIPATIVE)}",
        f"LAW_MEMORY = {bool(law_module.MEMORY)}",
        f"LAW_JUMPS = {bool(law_module.JUMPS)}",
        # the shifted approach phase of a point contact's tangent (docs/contact_laws.md 7)
        f"LAW_SHIFTED = {shifts and c.tangent != 'none' and c.model in POINT_MODELS}",
        f"LAW_DXI = {law_base(c.law) + getattr(law_module, 'TANGENT_SLOT', 0)}",
        f"GROUND = {ground_base(c)}",
        f"GROUND_Y = {c.ground_y}",
        f"GROUND_PERIODIC = {c.ground in ('sine', 'none')}",
        f"GROUND_KINKS = {bool(importlib.import_module(ground).KINKS)}",
        f"TANGENT = {c.tangent != 'none'}",  # vectors may ride along (their count: run time)
        f"ADAPTIVE = {method.adaptive}",
        f"NEW_EVALS = {method.new_evals}",
        f"DENSE_EVALS = {method.dense_evals}",
        f"DENSE_ROWS = {method.dense_rows}",
        f"ERROR_ORDER = {method.error_order}",
    ]
    if c.user is not None:
        u = c.user
        lines += [
            f"N_BASE = {u.n}",
            f"N_ENDS = {1 if u.gap is not None else 0}",
            f"USER_HAS_GAP = {u.gap is not None}",
            f"USER_BASE = {N_PARAMS}",
        ]
        if u.module is not None:
            rhs, jac, gap = u.names
            names = [f"{rhs} as user_rhs", f"{jac} as user_jacobian"]
            if gap is not None:
                names.append(f"{gap} as user_gap")
            lines.append(f"from {u.module} import " + ", ".join(names))
        if u.gap is None:
            lines.append("from chaospound.physics.models.user_support import no_gap as user_gap")
    return "\n".join(lines) + "\n"


def law_base(law: str) -> int:
    """First slot of a law's block in the packed vector.

    Hertz's block ``(beta, chi)`` is the scene's own contact slots ``P_BETA,
    P_CHI``; every other law's block follows the fixed layout, at ``N_PARAMS``
    (:meth:`chaospound.scene.Scene.pack` appends it).
    """
    return P_BETA if law == "hertz" else N_PARAMS


def law_block_size(law: str) -> int:
    """Slots of a law's block appended after ``N_PARAMS`` (0 for Hertz: its own slots)."""
    if law == "hertz":
        return 0
    module = importlib.import_module(LAWS[law])
    return len(module.PARAMETERS) + len(module.MEMORY)


def ground_base(c: Composition) -> int:
    """First slot of the ground motion's block.

    The x-only sine's block ``(period_ratio)`` is the scene's ``P_PERIOD_RATIO``;
    a record's or a stochastic motion's block (its samples), and the whole
    sine block ``(period_ratio, y_ratio, y_phase)`` of a composition with
    ``ground_y``, follow the law's block, after ``N_PARAMS``
    (:meth:`chaospound.scene.Scene.pack`).
    """
    if c.ground == "none" or (c.ground == "sine" and not c.ground_y):
        return P_PERIOD_RATIO
    return N_PARAMS + law_block_size(c.law)


def model_carries_memory(model: str) -> bool:
    """Whether a model's template defines the kernels that carry a law's memory
    (the onset velocity v0) in its tangent dynamics (:data:`MODEL_MEMORY_FUNCTIONS`)."""
    module = importlib.import_module(MODELS[model])
    return all(hasattr(module, name) for name in MODEL_MEMORY_FUNCTIONS)


def check_tangent(c: Composition) -> None:
    """Refuse tangent dynamics the engine cannot linearise exactly.

    Exact (docs/contact_laws.md section 7): a law with per-episode memory (the
    onset velocity v0, a function of the state and time of the onset) on a
    model that carries its sensitivity (towers, tower-wall, wall, pair); a law
    whose force jumps (Kelvin-Voigt): on a line contact the resultant is
    continuous at a corner onset and release and only the Jacobian jumps, on a
    point contact (wall, pair) the engine maps the tangent vectors by the
    saltation matrix at every onset and release
    (:func:`chaospound.engine.memory.saltation_tangent`); a point contact whose
    Jacobian is singular after every onset (Jankowski's): the engine integrates
    the approach phase's vectors shifted (``SHIFTED_TANGENT``,
    :func:`chaospound.engine.memory.shift_tangent`). Refused: memory on a model
    that does not carry it.

    Raises
    ------
    ValueError
        One line naming the law, the model, why, and the way out (the
        two-trajectory estimate, or a line-contact model).
    """
    if c.tangent == "none":
        return
    law = importlib.import_module(LAWS[c.law])
    if law.MEMORY and not model_carries_memory(c.model):
        raise ValueError(f"contact law {c.law!r} on the {c.model} model: Lyapunov exponents "
                         "and monodromy matrices are not available (its onset velocity v0 "
                         "is per-episode memory, whose sensitivity this model's tangent "
                         "dynamics do not carry); use the two-trajectory estimate "
                         "(chaospound.dynamics.lyapunov.largest_exponent_two_trajectory), "
                         "or a towers or tower-wall model")


def _footer(c: Composition) -> str:
    method = METHODS[c.method]
    return "\n".join([
        "# ---- the method's and the tangent's choices",
        f"step = {method.stepper}",
        f"dense_prepare = {method.dense}",
        f"rhs_grounded = {'rhs_plain' if c.tangent == 'none' else 'rhs_tangent'}",
        # a tangent run of a point contact whose force jumps maps its vectors by saltation;
        # it lands on the law's switch there and where a shifted approach phase ends
        # (N_ENDS is the model's, defined in its template body)
        "POINT_JUMPS = TANGENT and N_ENDS == 1 and LAW_JUMPS",
        "POINT_SWITCH = POINT_JUMPS or LAW_SHIFTED",
        # the loop, which Python calls, with its CPython wrapper and cached; the
        # others compile theirs if Python calls them (InternalDispatcher)
        "run = callable_from_python(run, _CACHED)",
    ]) + "\n"


def generate_source(c: Composition, cached: bool = True) -> str:
    """The text of the engine module of ``c`` (``cached``: its kernels on numba's disk cache).
    Compositions with the same :meth:`Composition.compiled` have the same text."""
    c = c.compiled()
    modules = (MODELS[c.model],) + TEMPLATES
    parts = [_template_text(m) for m in modules]
    decorators = ("from chaospound.kernels.jit import callable_from_python, "
                  "inline_internal as inline, kernel_internal as kernel\n"
                  f"_CACHED = {cached}")
    out = [f'"""Generated by chaospound.engine.compose for {c.canonical()}. Do not edit."""\n',
           decorators + "\n"]
    out += [prefix for prefix, _ in parts]
    out.append(_bindings(c))
    out += [body for _, body in parts]
    out.append(_footer(c))
    return "\n\n".join(out)


# ------------------------------------------------------------ keys and files

_DIGEST: list[str] = []


def source_digest() -> str:
    """sha256 of every module of the kernel packages (:func:`.kernels.cache.source_digest`),
    memoised per process."""
    if not _DIGEST:
        from ..kernels.cache import source_digest as digest

        _DIGEST.append(digest())
    return _DIGEST[0]


def composition_key(c: Composition) -> str:
    import numba

    text = "\0".join([TEMPLATE_VERSION, numba.__version__, sys.version, source_digest(),
                      c.compiled().canonical()])
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def cache_root() -> Path:
    """Where generated engines live: ``$CHAOSPOUND_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/chaospound``, else ``~/.cache/chaospound``."""
    explicit = os.environ.get("CHAOSPOUND_CACHE_DIR")
    if explicit:
        return Path(explicit)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "chaospound"


def _write_atomically(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:12]}.tmp")
    with open(temporary, "w") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(temporary, path)


# ------------------------------------------------------------------- engines


class Engine:
    """The compiled engine of one composition (a thin Python face of its module).

    ``module`` holds the kernels (``run``, ``rhs``, ``step``, ``model_*``, ...);
    :meth:`run_cycles` allocates the workspaces and runs the loop.
    """

    def __init__(self, composition: Composition, module: types.ModuleType, cached_file: bool):
        self.composition = composition
        self.module = module
        self.cached_file = cached_file
        self.propagate = composition.tangent == "propagator"  #: the loop's record at sections
        self._loaded = False

    def __repr__(self) -> str:
        return f"Engine({self.composition.label()})"

    def run_cycles(self, p, y, clock, k_record, k_end, rtol, atol, h_fixed, max_steps, restart,
                   n_samples, strobe, traj, imp, imp_state, stats, tangent_log) -> int:
        """The loop (:func:`chaospound.engine.loop.run`) with fresh workspaces."""
        n = y.shape[0]
        vectors = np.empty((MAX_STAGES + MAX_DENSE + 5, n))
        scalars = np.empty(N_SCALARS)
        ev_end = np.empty(MAX_EVENTS, dtype=np.int64)
        args = (p, y, clock, k_record, k_end, rtol, atol, h_fixed, max_steps, restart, n_samples,
                strobe, traj, imp, imp_state, stats, tangent_log, self.propagate, vectors,
                scalars, ev_end)
        if not self._loaded:
            self._load_loop(args)
        return self.module.run(*args)

    def _load_loop(self, args: tuple) -> None:
        """Compile the loop for ``args``, or load it from the disk cache, one process at a time.

        Processes that start on one composition together (sweep workers, Dask,
        pytest-xdist) would each compile it (10 s or more of CPU). Holding a lock
        beside the module's file while compiling lets the first compile and the
        others load its cache entry.
        """
        run = self.module.run
        if hasattr(run, "typeof_pyval"):  # not under NUMBA_DISABLE_JIT
            signature = tuple(run.typeof_pyval(a) for a in args)
            lock = Path(self.module.__file__).with_suffix(".lock") if self.cached_file else None
            with _machine_lock(lock):
                run.compile(signature)
        self._loaded = True

    def is_cached(self) -> bool | None:
        """Whether the loop's machine code is in numba's disk cache (None: unknown)."""
        if not self.cached_file:
            return False
        from ..kernels.jit import is_cached

        return is_cached(self.module.run)


@contextlib.contextmanager
def _machine_lock(path: Path | None):
    """Hold an exclusive ``flock`` on ``path`` (none when ``path`` is None, not POSIX or
    not writable); the kernel releases it if the holder dies."""
    fd = None
    if path is not None and fcntl is not None:
        with contextlib.suppress(OSError):
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    try:
        if fd is not None:
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        if fd is not None:
            os.close(fd)


_ENGINES: dict[Composition, Engine] = {}
#: modules built in memory, per compiled composition (those on file: ``sys.modules``)
_IN_MEMORY: dict[Composition, types.ModuleType] = {}
_LOCK = threading.Lock()


def engine_for(c: Composition) -> Engine:
    """The engine of a composition, generated and loaded once per process."""
    engine = _ENGINES.get(c)
    if engine is None:
        with _LOCK:
            engine = _ENGINES.get(c)
            if engine is None:
                engine = _load(c)
                _ENGINES[c] = engine
    return engine


def _load(c: Composition) -> Engine:
    check_tangent(c)
    if c.user is not None and c.user.module is None:
        return Engine(c, _load_in_memory(c), cached_file=False)
    source = generate_source(c)
    key = composition_key(c)
    folder = cache_root() / "composed"
    name = f"engine_{key}"
    path = folder / f"{name}.py"
    try:
        if not path.exists() or path.read_text() != source:
            _write_atomically(path, source)
    except OSError:  # a read-only cache: build in memory, compiled per process
        return Engine(c, _load_in_memory(c), cached_file=False)
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
    importlib.invalidate_caches()
    return Engine(c, importlib.import_module(name), cached_file=True)


def _load_in_memory(c: Composition) -> types.ModuleType:
    """The module built from text, uncached (user functions bound as objects), once per
    process and compiled composition."""
    key = c.compiled()
    module = _IN_MEMORY.get(key)
    if module is None:
        module = _IN_MEMORY[key] = _build_in_memory(key)
    return module


def _build_in_memory(c: Composition) -> types.ModuleType:
    source = generate_source(c, cached=False)
    module = types.ModuleType(f"chaospound_engine_{uuid.uuid4().hex[:12]}")
    if c.user is not None:
        module.user_rhs = c.user.rhs
        module.user_jacobian = c.user.jacobian
        if c.user.gap is not None:
            module.user_gap = c.user.gap
    exec(compile(source, f"<chaospound engine {c.label()}>", "exec"), module.__dict__)
    return module


def _name(fn) -> str:
    return getattr(fn, "py_func", fn).__name__


def _importable_module(*functions) -> str | None:
    """The module all the given jitted functions can be imported from by name, or None."""
    modules = set()
    for fn in functions:
        if fn is None:
            continue
        py = getattr(fn, "py_func", None)
        if py is None or py.__closure__ is not None or "<locals>" in py.__qualname__:
            return None
        module = sys.modules.get(py.__module__)
        if (module is None or py.__module__ == "__main__"
                or not getattr(module, "__file__", None)
                or getattr(module, py.__name__, None) is not fn):
            return None
        modules.add(py.__module__)
    return modules.pop() if len(modules) == 1 else None
