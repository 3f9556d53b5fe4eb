"""When ``auto`` takes fixed-step Runge-Kutta 4 instead of Adams: the step is held by stability.

An explicit or Adams method cannot step much past 1/|λ| of the fastest mode of the Jacobian,
whatever the tolerance: where that, not accuracy, holds the step, the method with the larger
stability region per evaluation wins. CVODES's Adams (functional iteration, orders up to 12)
is stable to about |hλ| ~ 0.2..2 at 1.5..2 evaluations a step; the classical RK4 to
|hλ| ~ 2.6..2.8 at 4. So ``auto`` takes RK4 when (``rk4_choice``):

1. RK4 at the largest step its stability allows on the eigenvalues (``rk4_stable_step``,
   SAFETY below the edge) costs less than MARGIN times Adams's floor: the evaluations per
   radian of the fastest mode over the run that Adams held by that mode's stability takes
   (``adams_floor``); and
2. at that step the global error is within the asked tolerance, by step doubling over a trial
   stretch at the start (``trial_error``): the error of RK4 at h estimated from the difference
   to h/2 (16/15 of it: fourth order) at the middle and the end of the stretch, its growth
   between them carried on linearly to the horizon. A step too long for the tolerance is
   shortened by the fourth root of the excess and checked again; if RK4 then costs more than
   MARGIN times Adams's floor, Adams it is.

Adams's floor is an estimate from runs where the fastest mode's stability held CVODES's Adams
(its evaluations nearly the same from rtol 1e-1 to 1e-3): 1.96 evaluations per radian of
|λ|max over the run where that mode is a real decay (16-link point-mass chains on 0.1 m
links), 2.8 to 3.2 where it rings (``tests/scenes/follower.py``, 300 rad/s) and up to 4.5 on
16-link chains with stiff joint springs: Adams-Moulton's stability region reaches further
along the negative real axis than along the imaginary one, where RK4's reaches 2.8.
"""

import math

import numpy as np

#: below the stability edge of RK4 on the Jacobian's eigenvalues: the spectrum moves as the
#: mechanism does, and the edge itself does not damp the fast modes
SAFETY = 0.7
#: CVODES's Adams held by stability: evaluations per radian of the fastest mode, where it
#: decays on the real axis and where it rings on the imaginary one (see above)
ADAMS_REAL, ADAMS_IMAGINARY = 2.0, 4.0
#: RK4 is taken when its evaluations are at most this fraction of Adams's floor: a margin for
#: the trial stretch and for an Adams that does a little better than its floor
MARGIN = 0.7
#: the trial stretch of the step-doubling check: this fraction of the run, at least
#: TRIAL_STEPS steps of RK4 (6 evaluations a step: RK4 at h and at h/2)
TRIAL_FRACTION = 0.05
TRIAL_STEPS = 16
#: and at most this many (the trial steps in Python: bounded work whatever the horizon, a
#: linearisation at t = 1e300 included; beyond, the error's growth is extrapolated)
TRIAL_MAX_STEPS = 512
#: the global error predicted by the trial at most this fraction of the tolerance
ERROR_SHARE = 0.5


def _rk4_gain(z):
    """The stability function of the classical RK4 at z = h λ."""
    return 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24


def rk4_stable_step(eigenvalues):
    """The longest step at which RK4 is stable on every one of ``eigenvalues`` (|R(hλ)| <= 1),
    a mode that grows (Re λ > 0) taken as undamped (its growth is the solution, followed for
    accuracy). inf without eigenvalues."""
    lam = np.asarray(eigenvalues, dtype=complex)
    lam = np.minimum(lam.real, 0.0) + 1j * lam.imag
    lam = lam[np.abs(lam) > 0]
    if not lam.size:
        return math.inf
    # along each ray of the complex plane RK4's region is an interval from 0 (|z| < 2.9)
    fractions = np.linspace(0.0, 3.0, 601)[1:]
    rays = fractions[None, :] * (lam / np.abs(lam))[:, None]
    unstable = np.abs(_rk4_gain(rays)) > 1 + 1e-12
    # the last stable fraction along each ray (none: 0; all: the whole 3)
    first = np.where(unstable.any(axis=1), np.argmax(unstable, axis=1), len(fractions))
    reach = np.where(first > 0, fractions[np.maximum(first - 1, 0)], 0.0)
    return float(np.min(reach / np.abs(lam)))


def rk4(rhs, t, x, h, steps):
    """``steps`` steps of the classical RK4 from (t, x): the end state."""
    for _ in range(steps):
        k1 = rhs(t, x)
        k2 = rhs(t + h / 2, x + h / 2 * k1)
        k3 = rhs(t + h / 2, x + h / 2 * k2)
        k4 = rhs(t + h, x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += h
    return x


def trial_error(rhs, t0, t_end, x0, h, rtol, atol):
    """The global error of RK4 at step ``h`` over [t0, t_end] predicted from a trial stretch
    at its start, in units of the tolerance (max over states of |e| / (atol + rtol |x|)).

    The error of RK4 at h is estimated by step doubling (16/15 of its difference to RK4 at
    h/2: fourth order) at the middle and at the end of the stretch; the error predicted for
    the run is the larger of the two, plus the growth between them extrapolated linearly to
    the horizon (an error that a damped mode carries away does not grow; one in the phase of
    the motion grows with time). inf when the trial blows up. Also the evaluations it took.
    """
    steps = min(TRIAL_MAX_STEPS, max(TRIAL_STEPS, math.ceil(TRIAL_FRACTION * (t_end - t0) / h)))
    steps = 2 * math.ceil(min(steps, max(2, math.ceil((t_end - t0) / h))) / 2)
    x0 = np.asarray(x0, float)
    errors = []
    with np.errstate(all="ignore"):
        coarse, fine, t = x0, x0, t0
        for _ in range(2):
            coarse = rk4(rhs, t, coarse, h, steps // 2)
            fine = rk4(rhs, t, fine, h / 2, steps)
            t += h * steps / 2
            scale = atol + rtol * np.maximum(np.abs(fine), np.abs(x0))
            errors.append(np.max(np.abs(coarse - fine) * 16 / 15 / scale) if len(x0) else 0.0)
    if not np.all(np.isfinite(errors)):
        return math.inf, 6 * steps
    half, end = float(errors[0]), float(errors[1])
    growth = max(0.0, end - half) / (h * steps / 2)
    return max(half, end) + growth * max(0.0, t_end - t), 6 * steps


def adams_floor(eigenvalues, span):
    """(|λ| of the fastest mode, the evaluations Adams takes over ``span`` when that mode's
    stability holds its step): ADAMS_REAL to ADAMS_IMAGINARY per radian, by the mode's
    direction."""
    if not len(eigenvalues):
        return 0.0, 0.0
    fastest = eigenvalues[np.argmax(np.abs(eigenvalues))]
    rate = float(abs(fastest))
    ringing = float(abs(fastest.imag)) / rate if rate else 0.0
    # Python floats: a rate near overflow (a scene about to blow up) gives inf, not numpy's
    # RuntimeWarning in the user's output
    return rate, (ADAMS_REAL + (ADAMS_IMAGINARY - ADAMS_REAL) * ringing) * rate * float(span)


def rk4_choice(rhs, t0, t_end, x0, spacing, eigenvalues, rtol, atol):
    """The step at which ``auto`` takes RK4 instead of Adams, and the evidence: (step or None,
    dict). ``spacing``: the output grid's (a step divides it)."""
    lam = np.asarray(eigenvalues, dtype=complex)
    span = t_end - t0
    rate, adams = adams_floor(lam, span)
    why = {"fastest_rate": rate, "adams_floor": adams}
    stable = float(SAFETY * rk4_stable_step(lam))
    if not math.isfinite(stable) or stable <= 0 or rate * span < 1:
        return None, why
    intervals = max(1, round(span / spacing))

    def plan(h):
        per = max(1, math.ceil(spacing / h * (1 - 1e-12)))
        return spacing / per, 4 * per * intervals

    h, cost = plan(stable)
    why.update(stable_step=stable, rk4_evaluations=cost)
    if cost > MARGIN * adams:
        return None, why
    spent = 0
    for _ in range(2):          # the step of the stability, then one shortened for accuracy
        error, took = trial_error(rhs, t0, t_end, x0, h, rtol, atol)
        spent += took
        why.update(predicted_error=error, trial_evaluations=spent)
        if error <= ERROR_SHARE:
            why.update(step=h, rk4_evaluations=cost)
            return h, why
        if not math.isfinite(error):
            return None, why
        h, cost = plan(0.9 * h * (ERROR_SHARE / error) ** 0.25)
        if cost + spent > MARGIN * adams:
            why.update(rk4_evaluations=cost)
            return None, why
    return None, why
