"""The background builder of an optimised library (``jit_tiers.py``), run as
``python -m kinetwork.solver.jit_background JOB``: it reads the job folder (the Functions'
serialisations, the library to build), removes it, and builds the library as ``jit`` builds a
foreground one, at a low priority. It holds the library's lock (inherited from the process
that started it) until it ends; a failure is written beside the library (``.failed``) so that
no later run tries again, and the lock file goes last.
"""

import contextlib
import json
import os
import pathlib
import shutil
import signal
import sys

import casadi as ca

from . import jit
from .jit_build import exit_on
from .jit_tiers import BACKGROUND_TIMEOUT, NICE, failed_marker


def main(argv):
    # stopped (SIGTERM): its compilers stopped and its build folder removed on the way out
    signal.signal(signal.SIGTERM, exit_on)
    job = pathlib.Path(argv[0])
    spec = json.loads((job / "job.json").read_text())
    functions = [ca.Function.deserialize((job / f"f{i}.casadi").read_text())
                 for i in range(spec["functions"])]
    shutil.rmtree(job, ignore_errors=True)
    lib = pathlib.Path(spec["library"])
    with contextlib.suppress(OSError):
        os.nice(NICE)
    try:
        jit.build_optimised(spec["name"], functions, lib, spec["jacobian"], BACKGROUND_TIMEOUT)
    except Exception as e:      # noqa: BLE001 (any failure is said to the runs that wait)
        with contextlib.suppress(OSError):
            failed_marker(lib).write_text(f"{type(e).__name__}: {e}\n")
        return 1
    finally:
        with contextlib.suppress(OSError):
            os.unlink(spec["lock"])                 # still held: waiters see the outcome
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
