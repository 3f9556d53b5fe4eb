"""The compiled functions a run of a System uses, built once per System and kept beside it.

A ``System`` is not changed by running it: its compiled twins (C code through the JIT cache,
CasADi integrators' DAE functions, the midpoint rule's step) live here, in a table keyed by the
System that goes away with it. Building is serialised by one lock, so threads that simulate
the same System at once build each function once.

The integration functions (``rhs``, ``jacobian``, ``dae``, ``dae_scaled``) are those of the
equations the integrators see: with relations (``system.relations``), each held at a value
between events, their parameters [p; r] (``Run.p_solver``); without, the System's own, of p.
"""

import collections
import threading
import weakref

import casadi as ca
import numpy as np

from ..equations.relations import JACOBIAN_JIT_LIMIT, jacobian_instructions
from . import jit as _jit

#: checked run settings kept per System (``Compiled.checked``), least recently used dropped
SETTINGS_KEPT = 64

#: replay recipes kept per System (``replay.py``: settings and parameter values), least
#: recently used dropped
RECIPES_KEPT = 64

#: CasADi integrators kept per System (the chunks of recent runs), least recently used dropped:
#: at least INTEGRATORS_KEPT, and as many as INTEGRATOR_VALUES / (states) allows up to
#: INTEGRATORS_MOST. A run with events has a chunk of its own grid after each event, and the
#: same run again has the same chunks: EngineV6's (22 states) are 341 integrators of ~40 kB,
#: 13 MB kept that were built again on every run (0.3 s of its 3.4 s) when 64 were kept
INTEGRATORS_KEPT = 64
INTEGRATORS_MOST = 1024
INTEGRATOR_VALUES = 20_000

_TABLE = weakref.WeakKeyDictionary()
_LOCK = threading.RLock()


class Compiled:
    """The compiled functions of one System (see ``compiled``)."""

    def __init__(self, system):
        self._system = weakref.ref(system)
        self._cache = {}
        self._integrators = collections.OrderedDict()
        self._checked = collections.OrderedDict()
        self._recipes = collections.OrderedDict()

    @property
    def system(self):
        return self._system()

    @property
    def held(self):
        """The equations the integrators see: ``Held`` of the System."""
        return self._get("held", lambda: Held(self.system))

    def _get(self, key, build):
        with _LOCK:
            if key not in self._cache:
                self._cache[key] = build()
            return self._cache[key]

    def _external(self, f, jacobian, options):
        return _jit.external(f, jacobian, **options)

    # -- the functions -----------------------------------------------------------------------
    def rhs(self, jit=None, jacobian=False):
        """The right-hand side as a Function of (t, x, p): CasADi's SX, or C when ``jit``
        (a dict of options for ``jit.external``: stats, required, deadline, cancelled)."""
        held = self.held
        if not jit:
            return held.f_rhs
        jacobian = jacobian and self.jacobian_small()
        return self._get(("rhs", jacobian),
                         lambda: self._external(held.f_rhs, jacobian, jit))

    def jacobian(self, jit=None):
        """d(xdot)/dx as a Function of (t, x, p), compiled when small enough."""
        held = self.held
        if not (jit and self.jacobian_small()):
            return held.jacobian_function()
        return self._get("jac", lambda: self._external(held.jacobian_function(), False, jit))

    def outputs(self, jit=None):
        """The probe signals as a Function of (t, x_full, p)."""
        system = self.system
        if not (jit and system.signals):
            return system.f_out
        return self._get("outputs", lambda: self._external(system.f_out, False, jit))

    def dependent(self, jit=None):
        """The loops' Jacobian in the dependent speeds (``System.f_dependent``, of (x, p)) as
        a Function of (t, x, p), t unused (what ``buffers.PointsBySize`` passes), compiled
        when ``jit``: the loops' watch reads it at every output (EngineV6 in CasADi's VM: 13
        us a point, a third of the watch)."""
        def of_time():
            f = self.system.f_dependent
            t, x = ca.SX.sym("t"), ca.SX.sym("x", f.size1_in(0))
            p = ca.SX.sym("p", f.size1_in(1))
            return ca.Function("dependent_jacobian", [t, x, p], [f.call([x, p])[0]])
        f = self._get("dependent", of_time)
        if not jit:
            return f
        return self._get(("dependent", "jit"), lambda: self._external(f, False, jit))

    def relations(self, name, jit=None):
        """The Function ``name`` of the System's relations (``equations.relations``:
        f_state, f_level, f_select), compiled when ``jit``: the indicators' rates read the
        whole equations, and locating an event evaluates them many times."""
        f = getattr(self.system.relations, name)
        if not jit:
            return f
        return self._get(("relations", name), lambda: self._external(f, False, jit))

    def jacobian_small(self):
        """Whether the exact Jacobian is small enough to compile (a Jacobian costs about
        operations x states: one that cannot pass is not even built)."""
        def decide():
            system, held = self.system, self.held
            if held.relations is not None:      # counted when the System was kept
                count = held.relations.jacobian_instructions(JACOBIAN_JIT_LIMIT)
            else:
                count = jacobian_instructions(
                    held.f_rhs or held.f_dae, system.n_states + system.n_algebraic,
                    held.jacobian_function, JACOBIAN_JIT_LIMIT)
            return count is not None and count <= JACOBIAN_JIT_LIMIT
        return self._get("jacobian_small", decide)

    def dae(self, jit=None, jacobian=False, hidden=False):
        """The equations as CasADi's integrators take them, in the time tau since the start of
        a chunk: their parameters are the model's then that start t0 (t = t0 + tau), so one
        integrator serves every chunk of the same length. A dict of SX (VM), or an MX
        Function of (tau, x, z, [p; t0], u) around the compiled code (CasADi's integrators
        compile nothing themselves unless handed a compiled Function).

        ``jacobian``: the method iterates with Newton. Without (Adams' functional iteration)
        the equations hide their derivatives in x when their Jacobian is large
        (``_equations``), or whatever its size when ``hidden``: for an integrator built for
        one chunk's own grid (after an event), whose creation would otherwise build the
        Jacobian function that functional iteration never calls (EngineV6: 0.39 ms of CPU an
        integrator, 0.14 ms hidden, 349 of them in its first run; the hiding node's 0.1-0.3
        us an evaluation over the chunk's hundred evaluations is less)."""
        return self._dae("dae", False, jit, jacobian, hidden and not jacobian)

    def dae_scaled(self, jit=None, jacobian=False):
        """The equations over a stretch of any length dt, in s = (t - t0) / dt from 0 to 1
        (d/ds = dt d/dt): parameters [p; t0; dt], so one integrator to s = 1 reaches any time
        (the events' trial times). As ``dae``: SX, or an MX Function around compiled code."""
        return self._dae("dae_scaled", True, jit, jacobian)

    def _dae(self, name, scaled, jit, jacobian, hidden=False):
        """``dae`` (t = t0 + tau) or, ``scaled``, ``dae_scaled`` (t = t0 + s dt, the rates
        times dt), each built once per kind."""
        system, held = self.system, self.held
        n_extra = 2 if scaled else 1            # t0, and dt when scaled

        def clock(tau, extra):
            """t, and dt/dtau when it is not 1 (the rates are multiplied by it)."""
            return (extra[0] + tau * extra[1], extra[1]) if scaled else (extra[0] + tau, None)

        def rates(ode, factor):
            return ode if factor is None else factor * ode
        if not jit and (jacobian or not (hidden or self._no_newton_vm())):
            def build_sx():
                tau, extra = ca.SX.sym("tau"), ca.SX.sym("extra", n_extra)
                t, factor = clock(tau, extra)
                return {"x": held.x, "z": held.z, "p": ca.vertcat(held.p, extra), "t": tau,
                        "ode": rates(ca.substitute(held.ode, held.t, t), factor),
                        "alg": ca.substitute(held.alg, held.t, t)}
            return self._get(f"{name}_sx", build_sx)
        exact = jacobian and bool(jit) and self.jacobian_small()
        def build():
            tau, x = ca.MX.sym("tau"), ca.MX.sym("x", system.n_states)
            z = ca.MX.sym("z", system.n_algebraic)
            pt, empty = ca.MX.sym("p", held.p.numel() + n_extra), ca.MX(0, 1)
            t, factor = clock(tau, pt[-n_extra:])
            ode, alg = self._equations(jit, exact, jacobian, t, x, z, pt[:-n_extra], hidden)
            return ca.Function(name, [tau, x, z, pt, ca.MX.sym("u", 0)],
                               [rates(ode, factor), alg, empty, empty], ca.dyn_in(),
                               ca.dyn_out())
        return self._get((name, bool(jit), exact, jacobian, hidden), build)

    def _equations(self, jit, exact, newton, t, x, z, p, hidden=False):
        """(ode, alg) in MX: the compiled code (or, without ``jit``, the SX Function in
        CasADi's VM), with its exact Jacobian when ``exact``.

        Without ``newton`` the states enter through ``stop_diff``: a CVODES integrator builds
        its DAE's Jacobian function when it is created, even for Adams' functional iteration
        that never evaluates it, and that Jacobian, by finite differences of the compiled code
        over a dense pattern, grew as N^2.5 to set up (24 s per integrator at 1024 links, and a
        run makes two or three; bench/results/study_scaling_setup.md). Hidden, the set-up takes
        0.04 s there and the run is the same to the last bit. Only where the Jacobian is large
        (``jacobian_small``): the hiding node costs every evaluation of the equations 0.1-0.3
        us in CasADi's virtual machine around the compiled code (8-10 % of the seed's run,
        ``bench/study_overhead.py``), and a small Jacobian's set-up costs under 1 ms, unless
        ``hidden`` (``dae``)."""
        held = self.held
        if not newton and (hidden or not self.jacobian_small()):
            x = ca.stop_diff(x, 1)
        if self.system.n_algebraic:
            f = self._external(held.f_dae, exact, jit) if jit else held.f_dae
            return f(t, x, z, p)
        return (self.rhs(jit, exact) if jit else held.f_rhs)(t, x, p), ca.MX(0, 1)

    def _no_newton_vm(self):
        """Whether an integrator without Newton runs in the VM around the SX Function, its
        derivatives hidden, rather than on the SX expressions: when the exact Jacobian is
        too large, which CasADi would build symbolically at the integrator's creation
        (a 1024-link chain: 15 GB)."""
        return self.system.n_algebraic == 0 and not self.jacobian_small()

    def integrator(self, key, build):
        """A CasADi integrator built once for ``key`` (its grid and options): the same chunks
        of the same run, again, reuse it. Only the most recent are kept (``integrators_kept``)."""
        return _kept(self._integrators, key, build, self.integrators_kept())

    def integrators_kept(self):
        """How many integrators are kept: INTEGRATORS_KEPT, or more for a model of few states
        (INTEGRATOR_VALUES / states, at most INTEGRATORS_MOST)."""
        system = self.system
        size = max(1, system.n_states + system.n_algebraic)
        return max(INTEGRATORS_KEPT, min(INTEGRATORS_MOST, INTEGRATOR_VALUES // size))

    def checked(self, key, check):
        """What ``check()`` answers for run settings ``key`` (``plan._checked``), found once:
        the answers of the most recent SETTINGS_KEPT settings are kept. A refusal (an
        exception) is not kept: it is raised again, found again."""
        return _kept(self._checked, key, check, SETTINGS_KEPT)

    def recipe(self, key, build=None):
        """The replay recipe kept for ``key`` (``replay.py``), made by ``build()`` when missing
        and ``build`` is given (else None). Only the most recent RECIPES_KEPT are kept."""
        if build is None:
            with _LOCK:
                found = self._recipes.get(key)
                if found is not None:
                    self._recipes.move_to_end(key)
                return found
        return _kept(self._recipes, key, build, RECIPES_KEPT)

    def memo(self, key, build):
        """Anything else a method builds once per System (the midpoint rule's step)."""
        return self._get(("memo", key), build)


class Held:
    """The equations the integrators see, of (t, x, z, p): with relations, each held at a
    value (``p`` = [model parameters; held values]); without, the System's own."""

    def __init__(self, system):
        eq, a = system.eq, system.asm
        self.relations = rel = system.relations
        self.t, self.x, self.z = a.t, eq.x, eq.z
        if rel is None:
            self.p, self.ode, self.alg = a.p, eq.ode, eq.alg
            self.f_rhs, self.f_dae = system.f_rhs, system.f_dae
            self.jacobian_function = system.jacobian_function
        else:
            self.p, self.ode, self.alg = rel.p, rel.ode, rel.alg
            self.f_rhs, self.f_dae = rel.f_rhs, rel.f_dae
            self.jacobian_function = rel.jacobian_function


def _kept(table, key, build, most):
    """``table[key]``, built by ``build()`` when missing: ``table`` (an OrderedDict) keeps
    the ``most`` recently used. An exception of ``build`` is not kept."""
    with _LOCK:
        if key in table:
            table.move_to_end(key)
            return table[key]
    made = build()
    with _LOCK:
        table[key] = made
        while len(table) > most:
            table.popitem(last=False)
    return made


def compiled(system):
    """The ``Compiled`` functions of ``system``, made on first use."""
    with _LOCK:
        if system not in _TABLE:
            _TABLE[system] = Compiled(system)
        return _TABLE[system]


def numeric(f, p, n_states):
    """A fast Python callable ``(t, x) -> ndarray`` of a Function of (t, x, p).

    Uses ``Function.buffer``: ~0.5 us a call instead of ~16 us for a plain call, which is what
    scipy's integrators pay on every right-hand-side evaluation.
    """
    buf, trigger = f.buffer()
    t_in, x_in = np.zeros(1), np.zeros(n_states)
    p_in = np.array(p, dtype=float)
    shape = f.size_out(0)
    out = np.zeros(shape[0] * shape[1])          # dense, column-major like CasADi
    for i, arr in enumerate((t_in, x_in, p_in)):
        buf.set_arg(i, memoryview(arr))
    buf.set_res(0, memoryview(out))

    # CasADi keeps raw pointers: the buffer and every array must outlive the trigger
    def call(t, x, _keep=(buf, p_in)):
        t_in[0] = t
        x_in[:] = x
        trigger()
        return out.reshape(shape, order="F").copy() if shape[1] > 1 else out.copy()
    return call
