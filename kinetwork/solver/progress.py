"""A progress bar for a run: ``simulate(..., progress=True)`` and ``kinetwork run --progress``.

The driver reports the simulated time it has reached now and then (between the chunks of its
integration); this turns those reports into a tqdm bar over the run's time span. The bar
appears only once a run has lasted ``DELAY`` seconds, so short runs print nothing.
"""

import contextlib
import os
import sys

#: seconds of a run before its bar appears (tqdm's ``delay``): a quick run shows none
DELAY = 1.0

BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| t = {n:.3g} of {total:g} s [{elapsed}<{remaining}]"


@contextlib.contextmanager
def progress_bar(t_start, t_end, desc="simulate", file=None, delay=None):
    """A callable ``report(t)`` that moves a tqdm bar from ``t_start`` to ``t_end``.

    Parameters
    ----------
    t_start, t_end : float
        The run's time span [s].
    desc : str
        The bar's label (the model's name).
    file : file object, optional
        Where the bar is drawn; default: a duplicate of stderr's descriptor, so the bar stays
        on the terminal while the integrators' own printing is captured.
    delay : float, optional
        Seconds before the bar is first drawn; default ``DELAY``.
    """
    from tqdm import tqdm
    own = None
    if file is None:
        try:
            own = file = os.fdopen(os.dup(sys.stderr.fileno()), "w")
        except (AttributeError, OSError, ValueError):   # stderr without a descriptor
            file = sys.stderr
    span = max(float(t_end) - float(t_start), 0.0)
    bar = tqdm(total=round(span, 9), file=file, unit="s", desc=desc, bar_format=BAR_FORMAT,
               leave=False, delay=DELAY if delay is None else delay)
    try:
        yield lambda t: bar.update(max(0.0, min(float(t) - t_start, span) - bar.n))
    finally:
        bar.close()
        if own is not None:
            own.close()
