"""The three decorators of the numba kernels.

``kernel`` compiles a function that only reads and writes arrays its caller
allocated. It is built without numba's reference-counting runtime (NRT), so
numba emits no atomic incref/decref around array arguments and views, and
with numpy's error model, so a division is a division (no zero test and
Python exception path; a zero divisor gives inf or NaN, which the
integrators report as a non-finite state).

``inline`` is ``kernel`` plus LLVM's always-inline: the model bodies, the
contact law and the ground motion, which then compile into one flat
right-hand side (``rhs_tangent`` of :mod:`chaospound.engine.glue`) instead of a
chain of calls that each pass three arrays field by field.

``driver`` compiles kernels that allocate their own workspaces and so need the
runtime (the engines do not: :class:`chaospound.engine.compose.Engine`
allocates in Python).

All three cache their machine code on disk (``__pycache__``, or
``NUMBA_CACHE_DIR``; :mod:`.cache` clears that cache when a kernel module
changes). What they cost and save per step is measured by
``benchmarks/bench_simulate.py`` (results/bench_simulate.json). None builds the
C-callable wrapper numba adds by default (``no_cfunc_wrapper``): nothing calls
a kernel through a C function pointer, so it was compiled for nothing.

A generated engine module binds ``kernel`` and ``inline`` to
:data:`kernel_internal` and :data:`inline_internal` instead: the same code,
compiled for other kernels only (:class:`InternalDispatcher`), except its loop.
"""

from numba import _dynfunc, config, njit
from numba.core import compiler, types
from numba.core.codegen import JITCodeLibrary
from numba.core.compiler_machinery import register_pass
from numba.core.registry import CPUDispatcher
from numba.core.typed_passes import NativeLowering

from .cache import invalidate_stale_cache

invalidate_stale_cache()  # before any kernel is defined, so before any is loaded


class KernelDispatcher(CPUDispatcher):
    """A dispatcher that compiles a kernel once per argument *type* when another
    kernel calls it, not once per constant value.

    numba types a constant argument at a call site by its value
    (``Literal[int](0)``, ``Literal[bool](True)``) and compiles the callee
    again for each such value: the engine's loop called ``end_value``,
    ``locate_root``, ``update_peak``, ``record_onset`` ... with a constant in one
    place and a variable in another, and numba typed, lowered and optimised
    each of them two or three times per composition (about a quarter of an
    engine's compile time). Constants still reach the machine code: LLVM
    propagates them after inlining. The arithmetic is the same, so the results
    are bitwise the same (benchmarks/golden.py).
    """

    def get_call_template(self, args, kws):
        args = tuple(types.unliteral(a) for a in args)
        kws = {name: types.unliteral(a) for name, a in kws.items()}
        return super().get_call_template(args, kws)


class _LinkOnlyLibrary(JITCodeLibrary):
    """A code library whose module is only ever linked into other libraries.

    Finalising it neither optimises its module nor hands it to the JIT engine.
    The engine would emit machine code for it, and for every kernel it links in,
    that nothing calls. And numba would run LLVM's function passes and its full
    module pipeline on it, over every kernel it links in, at every level of the
    call tree (the loop links the step, which links the right-hand side, which
    links the model, ...): the one full pipeline that optimises the loop's module,
    all of them linked in, does that work once, as a C compiler optimises one
    translation unit. Without fast-math flags LLVM's optimisations keep IEEE
    arithmetic, so the results are bitwise the same (benchmarks/golden.py); what it
    saves and costs is measured in docs/design/engine.md, section 6.3.
    This and the two classes below override numba internals (checked by
    :data:`_LINK_ONLY`; tests/test_compose.py checks the effect): with a numba
    that lacks them, internal kernels compile as before, machine code and all.
    """

    def _optimize_functions(self, ll_module):
        # the data layout is what numba's own version sets besides optimising
        ll_module.data_layout = self._codegen._data_layout

    def _optimize_final_module(self):
        pass  # the caller that Python calls optimises the whole linked module

    def _finalize_final_module(self):
        self._finalize_dynamic_globals()
        self._verify_declare_only_symbols()
        self._finalized = True


@register_pass(mutates_CFG=True, analysis_only=False)
class _LinkOnlyLowering(NativeLowering):
    """numba's lowering pass, into a :class:`_LinkOnlyLibrary`, with no executable made."""

    _name = "chaospound_link_only_lowering"

    def run_pass(self, state):
        if state.library is None:
            state.library = _LinkOnlyLibrary(state.targetctx.codegen(),
                                             state.func_id.func_qualname)
        state.flags.no_compile = True
        super().run_pass(state)
        lowered, library = state.cr, state.library
        fndesc = lowered.fndesc
        # the key callers find the function by: a function object that is never called
        # (Python calls go to the twin), so it needs no machine code
        entry = _dynfunc.make_function(fndesc.lookup_module(), fndesc.qualname.split(".")[-1],
                                       "internal kernel", 0, lowered.env, (library,))
        state.targetctx.insert_user_function(entry, fndesc, [library])
        state.reload_init.extend(library._reload_init)
        state["cr"] = compiler._LowerResult(fndesc, lowered.call_helper, cfunc=entry,
                                            env=lowered.env)
        return True


class _LinkOnlyCompiler(compiler.Compiler):
    """numba's nopython pipeline with :class:`_LinkOnlyLowering` for its lowering."""

    def define_pipelines(self):
        pipeline = compiler.DefaultPassBuilder.define_nopython_pipeline(self.state)
        pipeline.passes = [(_LinkOnlyLowering if p is NativeLowering else p, d)
                           for p, d in pipeline.passes]
        pipeline.finalize()
        return [pipeline]


#: whether this numba has the internals the link-only pipeline overrides
_LINK_ONLY = (hasattr(compiler, "_LowerResult") and hasattr(_dynfunc, "make_function")
              and all(hasattr(JITCodeLibrary, name) for name in (
                  "_finalize_final_module", "_finalize_dynamic_globals",
                  "_verify_declare_only_symbols", "_optimize_functions",
                  "_optimize_final_module")))


class InternalDispatcher(KernelDispatcher):
    """A kernel compiled for other kernels: no wrappers, no machine code, not cached.

    A generated engine module (:mod:`chaospound.engine.compose`) holds about forty
    kernels whose code is linked into the engine's loop, the one Python calls.
    For each, numba would build a wrapper that converts Python objects (its IR
    lowered, optimised and emitted as machine code) and, with the disk cache
    on, pickle its machine code to disk: work wasted when the loop's machine
    code, theirs included, is what the cache serves. These kernels skip both,
    and their LLVM module is only ever linked into their callers, unoptimised
    (:class:`_LinkOnlyLibrary`): numba would otherwise emit machine code for
    each of them, and again for every kernel each links in, that nothing runs,
    and optimise each at every level of the call tree.
    A call from Python (tests, an analysis reading a model function) is
    served by a twin compiled with its wrapper on first use
    (:func:`callable_from_python`; on the disk cache when the module's
    ``_CACHED`` says so).
    """

    def __init__(self, py_func, locals=None, targetoptions=None):
        super().__init__(py_func, locals=locals, targetoptions=targetoptions,
                         pipeline_class=_LinkOnlyCompiler if _LINK_ONLY else compiler.Compiler)

    def add_overload(self, cres):
        # not inserted in the type-dispatch table that Python calls go through,
        # so every call from Python lands in _compile_for_args
        self.overloads[tuple(cres.signature.args)] = cres

    def _compile_for_args(self, *args, **kws):
        # numba's C dispatcher calls what this returns with the same arguments
        twin = getattr(self, "_twin", None)
        if twin is None:
            cache = bool(self.py_func.__globals__.get("_CACHED", False))
            twin = self._twin = callable_from_python(self, cache)
        return twin


def callable_from_python(dispatcher, cache: bool = True):
    """``dispatcher``, or if it is internal, its function compiled with its CPython wrapper
    (and on the disk cache if ``cache``), with the same options otherwise (forceinline kept)."""
    if not isinstance(dispatcher, InternalDispatcher):
        return dispatcher
    options = {k: v for k, v in dispatcher.targetoptions.items() if k != "no_cpython_wrapper"}
    return _jit(cache, **options)(dispatcher.py_func)


def _jit(cache: bool, dispatcher_class: type = KernelDispatcher, **options):
    """``njit(cache=cache, **options)`` building a ``dispatcher_class`` (a
    :class:`KernelDispatcher` unless told otherwise)."""
    targetoptions = dict(options, nopython=True, boundscheck=None)

    def wrap(func):
        if config.DISABLE_JIT:
            return func
        dispatcher = dispatcher_class(py_func=func, locals={}, targetoptions=targetoptions)
        if cache:
            dispatcher.enable_caching()
        return dispatcher

    return wrap


#: the options every kernel shares: no runtime, numpy's division, no C-callable wrapper
_KERNEL = dict(_nrt=False, error_model="numpy", no_cfunc_wrapper=True)
kernel = _jit(True, **_KERNEL)
inline = _jit(True, **_KERNEL, forceinline=True)
driver = njit(cache=True, error_model="numpy", no_cfunc_wrapper=True)


def is_cached(dispatcher) -> bool | None:
    """Whether numba's disk cache holds fresh machine code of a ``cache=True`` kernel.

    True when the kernel's index file (``*.nbi`` in its cache folder) exists, carries
    the stamp of the current source file (numba's freshness check), and has an entry
    compiled for this CPU; False when loading it will compile (the first run after
    installing or editing, or after :mod:`.cache` cleared the cache: 30-60 s);
    None when this numba version does not tell (its cache layout is private).
    """
    try:
        overloads = dispatcher._cache._cache_file._load_index()
        magic = dispatcher.targetctx.codegen().magic_tuple()
    except Exception:  # private numba API: any change means "unknown"
        return None
    return any(isinstance(key, tuple) and len(key) > 1 and key[1] == magic for key in overloads)


#: as :data:`kernel` and :data:`inline`, for other kernels (:class:`InternalDispatcher`:
#: no CPython wrapper, no disk cache; Python gets a twin): a generated engine's kernels
kernel_internal = _jit(False, InternalDispatcher, **_KERNEL, no_cpython_wrapper=True)
inline_internal = _jit(False, InternalDispatcher, **_KERNEL, no_cpython_wrapper=True,
                       forceinline=True)
