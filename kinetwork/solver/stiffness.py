"""What ``auto`` runs (``choose``): the stiffness test at the start of a run, and the
evidence that a running Adams is held by a mode's stability (``stability_held``), which the
driver's look (``fallback.py``) reads before it hands the run to BDF. Both read the
eigenvalues of the right-hand side's Jacobian, by central differences (2n evaluations, no
symbolic Jacobian of O(n^2))."""

import numpy as np

#: the stiffness test of ``auto``: see ``stiffness``
STIFF_HORIZON_STEPS = 1e3
STIFF_RATIO = 10.0


def _jacobian_fd(f, t, x):
    """Central finite differences: 2n evaluations, O(n) each; no O(n^2) symbolic Jacobian."""
    J = np.empty((len(x), len(x)))
    for i in range(len(x)):
        dx = 1e-6 * max(1.0, abs(x[i]))
        e = np.zeros(len(x))
        e[i] = dx
        J[:, i] = (f(t, x + e) - f(t, x - e)) / (2 * dx)
    return J


def stiffness(rhs, t_start, t_end, x0):
    """The stiffness test of the ``auto`` method, on the Jacobian at the initial state.

    ``rhs(t, x)`` is the right-hand side. With λ the eigenvalues of d(xdot)/dx at
    (t_start, x0), the fastest decay rate is σ = max(-Re λ) and the fastest other motion is
    ω = max(max Re λ, max |Im λ|). The problem is stiff when σ (t_end - t_start) >
    STIFF_HORIZON_STEPS (an explicit or Adams method would need over ~10^3 steps for stability
    alone) and σ > STIFF_RATIO ω (that decay is much faster than anything the solution must
    follow). An undamped mechanism is never stiff by this test (its eigenvalues come in ±λ
    pairs); a hard, heavily damped spring is.

    Returns (stiff, σ, ω).
    """
    J = _jacobian_fd(rhs, t_start, x0)
    with np.errstate(all="ignore"):
        lam = np.linalg.eigvals(J) if J.size and np.all(np.isfinite(J)) else np.zeros(0)
    if not np.all(np.isfinite(lam)) or lam.size == 0:
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
    J = _jacobian_fd(rhs, t, x)
    with np.errstate(all="ignore"):
        lam = np.linalg.eigvals(J) if J.size and np.all(np.isfinite(J)) else np.zeros(0)
    if lam.size == 0 or not np.all(np.isfinite(lam)):
        return False, 0.0, 0.0
    fastest = lam[np.argmax(np.abs(lam))]
    rate, decay = float(abs(fastest)), float(-fastest.real)
    low, high = STABILITY_HELD
    held = low <= step * rate < high and decay >= BDF_WEDGE * rate and \
        decay * (t_end - t) > STIFF_HORIZON_STEPS
    return held, rate, decay


def choose(run, keep=True):
    """What ``auto`` runs: (method names to try in order, why). IDAS for models with
    algebraic variables (loops compiled with ``loops="partition"``, massless junctions); else
    Adams (loops too: their default formulation is the projected ODE) unless the stiffness
    test says BDF, and BDF again when Adams fails.

    A model without damping (generalized forces independent of the speeds) is conservative
    up to its time-dependent drives: its eigenvalues come in ±λ pairs and it is never stiff by
    the test, so the test (an eigenvalue problem of 2n x 2n) is not run.

    ``keep``: the answer is kept per start, horizon and parameter values (a model run again
    asks the same); a sweep's members, each asking once, do not fill that table.
    """
    system = run.system
    if system.n_algebraic:
        return ["idas"], {"loops": system.formulation_note}
    why = {"stiff": False, "damped": system.damped}
    if system.damped:
        def test():
            return stiffness(run.rhs(), run.t_start, run.t_end, run.x0)
        # once per start, horizon and parameter values: a model run again asks the same
        key = ("stiffness", float(run.t_start), float(run.t_end),
               np.asarray(run.x0, float).tobytes(), np.asarray(run.p_solver, float).tobytes())
        stiff, sigma, omega = run.compiled.memo(key, test) if keep else test()
        why.update(stiff=bool(stiff), decay_rate=sigma, motion_rate=omega)
    return (["cvodes"] if why["stiff"] else ["cvodes-adams", "cvodes"]), why
