"""What the tolerance a user asks for means, and the tolerances the solvers get for it.

A user's ``rtol`` promises the global error: over the run, an angle (or any state of order
one) stays within about ``rtol`` of the exact solution, and within 100 x ``rtol`` on every
non-chaotic scene of ``bench/study_tolerance.py``. SUNDIALS' tolerances bound the error of
each step instead; the global error is their sum over thousands of steps, amplified by the
motion's own sensitivity (a four-bar swinging near its dead point amplifies an error of its
crank angle a hundredfold). So CVODES and IDAS get tighter tolerances than the ones asked
for: ``solver_tolerances``, calibrated by the study (the table there is the evidence).
"""

#: (method, the system has loops) -> how many times tighter than asked the solver's rtol and
#: atol are. Measured in bench/study_tolerance.py (global error / rtol as asked, worst over
#: its scenes and rtol 1e-4 .. 1e-10): trees under Adams ~1000 (the seed at large angles, the
#: drive train; erratic from one rtol to the next), loops ~9e4 under IDAS and Adams alike (the
#: four-bar swinging near its dead point; slider-crank 3e4, spatial four-bar 3e3)
TIGHTEN = {("cvodes-adams", False): 100.0, ("cvodes", False): 100.0, ("idas", False): 100.0,
           ("cvodes-adams", True): 1e4, ("cvodes", True): 1e4, ("idas", True): 1e4}
#: the smallest rtol each solver is given: below it the steps are spent on round-off, and
#: IDAS fails (at 1e-13 on the spatial four-bar, at 1e-14 on the four-bar). CVODES Adams on
#: the loops' projected ODEs still gains from 1e-13 to 1e-14 (the four-bar's crank error
#: 1.3e-8 -> 5e-11 over 10 s) and holds steady at 1e-15 (1.3e-10; the slider-crank 6e-10 ->
#: 3e-11): rtol 1e-10 asked of a loop model runs at 1e-14, and its error estimate's
#: repetition at 1e-15 still has a tighter tolerance than the run
RTOL_FLOOR = {"cvodes-adams": 1e-15, "cvodes": 1e-13, "idas": 1e-12}
#: set False to hand the solvers the tolerances as asked (the study's "before")
ENABLED = True


#: SUNDIALS' own step budget per output interval (mxstep) at the tolerances asked
MXSTEP = 10_000


def solver_tolerances(method, system, rtol, atol):
    """(rtol, atol, step budget) for the SUNDIALS solver of ``method`` (a ``methods.Casadi``)
    on ``system`` when ``rtol``, ``atol`` are asked: both divided by its TIGHTEN factor, rtol
    not below its RTOL_FLOOR (nor raised when asked below it), atol by as much as rtol; the
    budget of steps per output interval grows with the steps a tighter tolerance takes (at
    most factor^(1/5) more for a method of order 4 or more), so that a run fails where it
    failed before (a dead point the loop watch names) and not earlier."""
    adams = method.options.get("linear_multistep_method") == "adams"
    name = "cvodes-adams" if adams else method.plugin
    factor = TIGHTEN.get((name, _closes_loops(system)), 1.0) if ENABLED else 1.0
    if factor == 1.0:
        return rtol, atol, MXSTEP
    tight = max(rtol / factor, min(rtol, RTOL_FLOOR[name]))
    return tight, atol * tight / rtol, int(MXSTEP * (rtol / tight) ** 0.2)


def _closes_loops(system):
    """Whether ``system`` has loop constraints: its formulation is not the tree's, and a
    partition has algebraic variables (a cut free joint constrains nothing: a tree's run)."""
    if system.formulation == "partition":
        return system.n_algebraic > 0
    return system.formulation != "tree"
