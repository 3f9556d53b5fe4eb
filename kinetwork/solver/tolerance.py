"""What the tolerance a user asks for means, and the tolerances the solvers get for it.

A user's ``rtol`` promises the global error: over the run, an angle (or any state of order
one) stays within about ``rtol`` of the exact solution, and within 100 x ``rtol`` on every
non-chaotic scene of ``bench/study_tolerance.py``, over 10 s and over 100 s. SUNDIALS'
tolerances bound the error of each step instead; the global error is their sum over thousands
of steps, amplified by the motion's own sensitivity (a four-bar swinging near its dead point
amplifies an error of its crank angle a hundredfold). So CVODES and IDAS get tighter
tolerances than the ones asked for: ``solver_tolerances``, calibrated by the study over
HORIZON (the table there is the evidence), and tighter again for a longer run.

Why the square of the horizon: on a conservative oscillation whose period depends on its
amplitude (a pendulum, the four-bar, a chain swinging without a damper), each step's error
moves the motion onto a neighbouring orbit, of another period, and the phase error that makes
grows in proportion to the time left. Summed over a run of length T (steps in proportion to
T), the global error of a method that is not symplectic grows as T^2 times the tolerance
(Hairer, Lubich & Wanner, *Geometric Numerical Integration*, 2nd ed., X.3: linear error growth
only for symplectic methods). Measured: the four-bar's global error over 100 s is 40 to 360
times its error over 10 s at the same solver tolerance (quadratic); the undamped seed at
its small angles, an oscillation of nearly one period whatever its amplitude, 5 to 14 times
(linear). A damped motion forgets its errors and needs less; each is given the same, which
costs 1.2 to 1.7 times the steps over 100 s (median 1.5; results/study_tolerance_h100.md:
every entry there within 41 x rtol, 1480 x without the rule).
"""

#: (method, the system has loops) -> how many times tighter than asked the solver's rtol and
#: atol are over a run of up to HORIZON. Measured in bench/study_tolerance.py (global error /
#: rtol as asked, worst over its scenes and rtol 1e-4 .. 1e-10): trees under Adams ~1000 (the
#: seed at large angles, the drive train; erratic from one rtol to the next), loops ~9e4 under
#: IDAS and Adams alike (the four-bar swinging near its dead point; slider-crank 3e4, spatial
#: four-bar 3e3)
TIGHTEN = {("cvodes-adams", False): 100.0, ("cvodes", False): 100.0, ("idas", False): 100.0,
           ("cvodes-adams", True): 1e4, ("cvodes", True): 1e4, ("idas", True): 1e4}
#: the length of run [s] TIGHTEN is calibrated for; a longer run of length T is given
#: (T / HORIZON)^2 times tighter tolerances still (see the module's docstring), a shorter one
#: the same as HORIZON
HORIZON = 10.0
#: the smallest rtol each solver is given: below it the steps are spent on round-off, and
#: IDAS fails (at 1e-13 on the spatial four-bar, at 1e-14 on the four-bar). CVODES Adams on
#: the loops' projected ODEs still gains from 1e-13 to 1e-14 (the four-bar's crank error
#: 1.3e-8 -> 5e-11 over 10 s) and holds steady at 1e-15 (1.3e-10; the slider-crank 6e-10 ->
#: 3e-11): rtol 1e-10 asked of a loop model runs at 1e-14, and its error estimate's
#: repetition at 1e-15 still has a tighter tolerance than the run
RTOL_FLOOR = {"cvodes-adams": 1e-15, "cvodes": 1e-13, "idas": 1e-12}
#: set False to hand the solvers the tolerances as asked (the study's "before")
ENABLED = True
#: the steps a run may take per HORIZON of its length, at the tolerances asked: what a run on
#: the default grid (1000 output intervals) had when SUNDIALS' budget of MXSTEP steps was per
#: output interval, now the run's whatever its grid (issue 30: 11 outputs of a 128-link
#: chain ran out of steps where 1001 did not)
RUN_STEPS = 10_000_000
#: SUNDIALS' own budget per output interval (its mxstep), at the tolerances asked: what an
#: output interval may take at least, however short
MXSTEP = 10_000
#: at most this many steps for any run or interval (SUNDIALS counts them in a C long), and a
#: horizon counted as at most this many HORIZONs (1e300 s asked: no overflow; the floor and
#: the time limit bound such a run anyway)
MOST_STEPS = 10**15
LONGEST = 1e30


def solver_tolerances(method, system, rtol, atol, horizon=HORIZON):
    """(rtol, atol) for the SUNDIALS solver of ``method`` (a ``methods.Casadi``) on
    ``system`` when ``rtol``, ``atol`` are asked for a run of length ``horizon`` [s]: both
    divided by its TIGHTEN factor, and by (horizon / HORIZON)^2 when longer, rtol not below
    its RTOL_FLOOR (nor raised when asked below it), atol by as much as rtol."""
    factor = tightening(method, system, horizon)
    if factor == 1.0:
        return rtol, atol
    adams = method.options.get("linear_multistep_method") == "adams"
    floor = RTOL_FLOOR["cvodes-adams" if adams else method.plugin]
    tight = max(rtol / factor, min(rtol, floor))
    return tight, atol * tight / rtol


def tightening(method, system, horizon=HORIZON):
    """How many times tighter than asked ``method``'s tolerances are on ``system`` over a run
    of ``horizon`` [s], before the floor: 1 for a method that is not SUNDIALS'."""
    if not ENABLED or not getattr(method, "sundials", False):
        return 1.0
    adams = method.options.get("linear_multistep_method") == "adams"
    name = "cvodes-adams" if adams else method.plugin
    factor = TIGHTEN.get((name, _closes_loops(system)), 1.0)
    return factor * _length(horizon) ** 2


#: CVODES Adams's corrector (functional iteration: an evaluation of the equations each
#: iteration) stops when its estimated error is within this fraction of the step's error
#: tolerance, on equations of more than LOOSE_CORRECTOR_ABOVE instructions; CVODES's own 0.1
#: below. At 0.1 a step usually takes two iterations; at 0.3 many take one: fewer
#: evaluations, a few more steps. Measured (bench/work_precision_options.py; CPU time to the
#: same joint-angle error, 9 interleaved runs): on the 128-link point-mass chains (18k and
#: 54k instructions) 3-23 % less to 1e-4..1e-6 (3-D to 1e-4 on decades of rtol: 28 ms
#: against 46), within -7..+8 % to 1e-7..1e-10 with as many evaluations or fewer; on 16-link
#: ones (2k, 6k) up to 15 % more, a step's own cost there being near an evaluation's
LOOSE_CORRECTOR, LOOSE_CORRECTOR_ABOVE = 0.3, 15_000


def corrector_test(method, instructions):
    """CVODES options of ``method`` (a ``methods.Casadi``) for its corrector's convergence
    test on equations of ``instructions`` instructions: none but for Adams's functional
    iteration on large equations (LOOSE_CORRECTOR), and none where ``method`` sets it."""
    opts = method.options
    if opts.get("nonlinear_solver_iteration") != "functional" or "nonlin_conv_coeff" in opts \
            or instructions <= LOOSE_CORRECTOR_ABOVE:
        return {}
    return {"nonlin_conv_coeff": LOOSE_CORRECTOR}


def step_budget(method, system, horizon, interval=None):
    """The steps a run of ``method`` on ``system`` over ``horizon`` [s] may take: RUN_STEPS
    per HORIZON of its length (at least one HORIZON's), times the growth of the steps at the
    tighter tolerances it is given (factor^(1/5) for a method of order 4 or more).

    With ``interval`` [s]: the steps one output interval that long may take (SUNDIALS'
    mxstep), its length's share of the run's budget and at least MXSTEP (times the same
    growth): what a stretch of the run may take before the solver gives up on it (a dead
    point where the steps shrink to nothing), whatever the grid; the run's total is the
    driver's to count."""
    growth = tightening(method, system, horizon) ** 0.2
    run = RUN_STEPS * _length(horizon)
    if interval is None:
        return int(min(run * growth, MOST_STEPS))
    share = RUN_STEPS * min(abs(float(interval)) / HORIZON, LONGEST)
    return int(min(min(max(MXSTEP, share), run) * growth, MOST_STEPS))


def _length(horizon):
    """The length of a run in HORIZONs, at least one and at most LONGEST."""
    return min(max(1.0, abs(float(horizon)) / HORIZON), LONGEST)


def _closes_loops(system):
    """Whether ``system`` has loop constraints: its formulation is not the tree's, and a
    partition has algebraic variables (a cut free joint constrains nothing: a tree's run)."""
    if system.formulation == "partition":
        return system.n_algebraic > 0
    return system.formulation != "tree"
