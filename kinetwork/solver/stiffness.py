"""What ``auto`` runs (``choose``): the stiffness test at the start of a run, the choice of
fixed-step RK4 where stability, not accuracy, holds an explicit method's step (``explicit.py``),
and the evidence that a running Adams is held by a mode's stability (``stability_held``),
which the driver's look (``fallback.py``) reads before it hands the run to BDF. All read the
eigenvalues of the right-hand side's Jacobian (``spectrum``): all of them by central
differences (2n evaluations, no symbolic Jacobian of O(n^2)) for up to DENSE_STATES states,
the extreme ones by Arnoldi iteration on Jacobian-vector products above (a dense eigenvalue
problem of 2048 x 2048 took most of 44 s of CPU on a damped 1024-link chain)."""

import math

import numpy as np

from .explicit import rk4_choice

#: the stiffness test of ``auto``: see ``stiffness``
STIFF_HORIZON_STEPS = 1e3
STIFF_RATIO = 10.0
#: up to this many states, every eigenvalue of a dense Jacobian; above, the EXTREME
#: eigenvalues of largest modulus by ARPACK on Jacobian-vector products
DENSE_STATES = 192
EXTREME = 6


def _jacobian_fd(f, t, x):
    """Central finite differences: 2n evaluations, O(n) each; no O(n^2) symbolic Jacobian."""
    J = np.empty((len(x), len(x)))
    for i in range(len(x)):
        dx = 1e-6 * max(1.0, abs(x[i]))
        e = np.zeros(len(x))
        e[i] = dx
        J[:, i] = (f(t, x + e) - f(t, x - e)) / (2 * dx)
    return J


def _extreme(f, t, x):
    """The EXTREME eigenvalues of largest modulus of d(f)/dx at (t, x), matrix-free: ARPACK's
    Arnoldi iteration on central-difference Jacobian-vector products (2 evaluations each)."""
    from scipy.sparse.linalg import ArpackError, ArpackNoConvergence, LinearOperator, eigs
    n = len(x)
    size = max(1.0, float(np.linalg.norm(x)) / math.sqrt(n))

    def product(v):
        v = np.asarray(v, dtype=float).ravel()
        norm = float(np.linalg.norm(v))
        if norm == 0:
            return np.zeros(n)
        eps = 1e-6 * size / norm
        return (f(t, x + eps * v) - f(t, x - eps * v)) / (2 * eps)

    operator = LinearOperator((n, n), matvec=product, dtype=float)
    start = np.random.default_rng(0).standard_normal(n)       # the same answer every run
    try:
        return eigs(operator, k=EXTREME, which="LM", tol=1e-4, maxiter=50 * n, v0=start,
                    return_eigenvectors=False)
    except ArpackNoConvergence as exc:
        return exc.eigenvalues
    except ArpackError:
        return np.zeros(0)


def spectrum(rhs, t, x):
    """Eigenvalues of d(xdot)/dx at (t, x): all of them up to DENSE_STATES states, else the
    EXTREME of largest modulus (what bounds an explicit step, and what makes a problem stiff).
    Empty when the Jacobian is not finite."""
    x = np.asarray(x, dtype=float)
    with np.errstate(all="ignore"):
        if len(x) > DENSE_STATES:
            lam = _extreme(rhs, t, x)
        else:
            J = _jacobian_fd(rhs, t, x)
            lam = np.linalg.eigvals(J) if J.size and np.all(np.isfinite(J)) else np.zeros(0)
    lam = np.asarray(lam, dtype=complex)
    return lam if lam.size and np.all(np.isfinite(lam)) else np.zeros(0, dtype=complex)


def stiffness(rhs, t_start, t_end, x0, eigenvalues=None):
    """The stiffness test of the ``auto`` method, on the Jacobian at the initial state (its
    ``eigenvalues`` when known, by ``spectrum``).

    ``rhs(t, x)`` is the right-hand side. With λ the eigenvalues of d(xdot)/dx at
    (t_start, x0), the fastest decay rate is σ = max(-Re λ) and the fastest other motion is
    ω = max(max Re λ, max |Im λ|). The problem is stiff when σ (t_end - t_start) >
    STIFF_HORIZON_STEPS (an explicit or Adams method would need over ~10^3 steps for stability
    alone) and σ > STIFF_RATIO ω (that decay is much faster than anything the solution must
    follow). An undamped mechanism is never stiff by this test (its eigenvalues come in ±λ
    pairs); a hard, heavily damped spring is.

    Returns (stiff, σ, ω).
    """
    lam = spectrum(rhs, t_start, x0) if eigenvalues is None else eigenvalues
    if lam.size == 0:
        return False, 0.0, 0.0
    sigma = float(max(0.0, np.max(-lam.real)))
    omega = float(max(0.0, np.max(lam.real), np.max(np.abs(lam.imag))))
    stiff = sigma * (t_end - t_start) > STIFF_HORIZON_STEPS and sigma > STIFF_RATIO * omega
    return stiff, sigma, omega


#: a mean step times the fastest mode's rate in this band: the step is held by that mode's
#: stability (the stability regions of CVODES's Adams orders reach about 0.2 to 2 along the
#: axes); far below it, the step is held by accuracy (a tight rtol), not by that mode
STABILITY_HELD = (0.1, 3.0)
#: the decay rate of that mode at least this fraction of its rate (within 72.5 degrees of
#: the negative real axis): BDF of orders up to 4 is stable on it at any step, as it is not on
#: a lightly damped ringing (the seed at rest after a long run), where BDF would do no better
BDF_WEDGE = 0.3


def stability_held(rhs, t, t_end, x, step):
    """Whether a variable-step explicit or Adams method taking steps of ``step`` at (t, x) is
    held there by the stability of a mode that BDF steps over: the fastest mode of the
    Jacobian (rate |λ|) has step |λ| within STABILITY_HELD, it decays within what remains of
    the run (-Re λ (t_end - t) > STIFF_HORIZON_STEPS: gone early, not a motion the solution
    follows), and within BDF's stable wedge (-Re λ >= BDF_WEDGE |λ|). The evidence behind
    auto's switch from a stalled Adams to BDF.

    Returns (held, |λ|, -Re λ) of that mode."""
    lam = spectrum(rhs, t, x)
    if lam.size == 0:
        return False, 0.0, 0.0
    fastest = lam[np.argmax(np.abs(lam))]
    rate, decay = float(abs(fastest)), float(-fastest.real)
    low, high = STABILITY_HELD
    held = low <= step * rate < high and decay >= BDF_WEDGE * rate and \
        decay * (t_end - t) > STIFF_HORIZON_STEPS
    return held, rate, decay


def bdf_steps_over(eigenvalues, span):
    """Whether the fastest mode is one BDF steps over once it has decayed (within its wedge,
    gone within ``span``): where it holds an explicit step, the look at a running Adams hands
    the run to BDF (``fallback.py``), which beats RK4 there by far (a hard spring damped at
    2.5e5/s: under 10^4 BDF steps where RK4 would take 3.7e6)."""
    if not len(eigenvalues):
        return False
    fastest = eigenvalues[np.argmax(np.abs(eigenvalues))]
    decay = -fastest.real
    return bool(decay >= BDF_WEDGE * abs(fastest) and decay * span > STIFF_HORIZON_STEPS)


def choose(run, keep=True):
    """What ``auto`` runs: (method names to try in order, why). IDAS for models with
    algebraic variables (loops compiled with ``loops="partition"``, massless junctions); else
    BDF when the stiffness test says so; else fixed-step RK4 where the eigenvalues say the
    step of an explicit method is held by stability of a mode BDF does not step over
    (``bdf_steps_over``) and a trial says RK4 keeps the asked tolerance at the step they
    allow (``explicit.rk4_choice``: the run's ``step`` is set to it), Adams after it if it
    fails; else Adams (loops too: their default formulation is the
    projected ODE), and BDF when Adams fails.

    A model without damping (generalized forces independent of the speeds) is conservative
    up to its time-dependent drives: its eigenvalues come in ±λ pairs and it is never stiff by
    the test, so the test (an eigenvalue problem of 2n x 2n) is not run, and it gets Adams.

    ``keep``: the answers are kept per start, horizon, tolerances and parameter values (a
    model run again asks the same); a sweep's members, each asking once, do not fill that
    table.
    """
    system = run.system
    if system.n_algebraic:
        return ["idas"], {"loops": system.formulation_note}
    why = {"stiff": False, "damped": system.damped}
    if not system.damped:
        return ["cvodes-adams", "cvodes"], why
    start = (float(run.t_start), float(run.t_end), np.asarray(run.x0, float).tobytes(),
             np.asarray(run.p_solver, float).tobytes())

    def memo(key, fn):
        return run.compiled.memo(key + start, fn) if keep else fn()

    x0 = np.asarray(run.x0, float)[:system.n_states]
    lam = memo(("spectrum",), lambda: spectrum(run.rhs(), run.t_start, x0))
    stiff, sigma, omega = memo(("stiffness",), lambda: stiffness(
        run.rhs(), run.t_start, run.t_end, x0, eigenvalues=lam))
    why.update(stiff=bool(stiff), decay_rate=sigma, motion_rate=omega)
    if stiff:
        return ["cvodes"], why
    if run.events is None and system.f_dependent is None and not run.max_step and \
            len(run.grid) > 1 and not bdf_steps_over(lam, run.t_end - run.t_start):
        step, evidence = memo(("rk4", run.rtol, run.atol, run.spacing), lambda: rk4_choice(
            run.rhs(), run.t_start, run.t_end, x0, run.spacing, lam, run.rtol, run.atol))
        why["rk4"] = evidence
        if step is not None:
            run.step = step
            run.steps_per_interval = max(1, round(run.spacing / step))
            return ["rk", "cvodes-adams", "cvodes"], why
    return ["cvodes-adams", "cvodes"], why
