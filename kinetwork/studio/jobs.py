"""Child processes for the studio's work on models: no request can freeze the server, and
any work can be stopped at once.

A model from the page is untrusted input: checking it may take long (a unit written as a
power tower), compiling it holds the interpreter's lock inside CasADi for seconds, a run may
take minutes, and none of that can be interrupted in a thread. So every piece of work that
reads a model runs as one call in a child process forked from a *forkserver* that has
kinetwork imported (a fork costs milliseconds, not the half second of an import). The server
only waits on a pipe: a time limit or a cancel ends the child and its process group (the C
compiler it started goes too), and SIGINT stops the server at once.

A child reports through a :class:`Channel`: its progress (0..1) and phase, and whether it is
asked to stop. Its answer is what the function returns (any picklable value); an exception
becomes an :class:`ChildError` in the parent, with the child's traceback in the log.
"""

import asyncio
import contextlib
import io
import logging
import multiprocessing
import multiprocessing.context
import os
import signal
import threading
import time
import traceback

log = logging.getLogger("kinetwork.studio")

#: what the forkserver imports once, so that each child starts with it loaded: scipy.optimize
#: (0.3 s to import) is what a loop's start searched for (``equations/loopclose.search``) and
#: circuit junctions (``equations/junctions``) import on first use (events no longer do:
#: ``solver/roots.py``); the last one runs a small model there (``warm``), so that each child
#: starts warm too
PRELOAD = ["kinetwork", "kinetwork.graph.io", "kinetwork.equations", "kinetwork.solver.driver",
           "scipy.optimize", "kinetwork.studio.jobs", "kinetwork.studio.work",
           "kinetwork.studio.warm"]
#: environment variables a child takes from the server at each call (the forkserver's were
#: fixed when it started): kinetwork's own settings
ENV_PREFIX = "KINETWORK_"
#: phases a child reports (Channel.phase), by number
PHASES = ("starting", "checking", "compiling", "integrating", "writing results")
#: parts of an answer a child may send ahead of it (``Channel.ahead``): a run's results for
#: the plots, then its 3-D view's poses, each as soon as it is made
AHEAD = ("results", "animation")
#: after a cancel, the seconds a child has to stop by itself before it is ended (then SIGTERM,
#: and SIGKILL KILL_GRACE seconds after), by the phase it is in: before it computed anything
#: (nothing is lost), while integrating (it stops at its next chunk and keeps what it
#: reached), while writing the results it finished (kept: bounded by the size of results)
CANCEL_GRACE = {"starting": 0.5, "checking": 0.5, "compiling": 0.5, "integrating": 5.0,
                "writing results": 60.0}
KILL_GRACE = 0.2

_context = None
_context_lock = threading.Lock()


class TimeLimit(Exception):
    """The call took longer than its limit; the child was ended."""


class ChildError(Exception):
    """The child raised: ``kind`` is the exception's type name, ``text`` its message."""

    def __init__(self, kind, text):
        super().__init__(f"{kind}: {text}")
        self.kind, self.text = kind, text


def context():
    """The multiprocessing context of the studio's children: a forkserver with kinetwork
    imported where the platform has one (Linux, macOS), else spawn."""
    global _context
    with _context_lock:
        if _context is None:
            method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() \
                else "spawn"
            _context = multiprocessing.get_context(method)
            if method == "forkserver":
                _context.set_forkserver_preload(PRELOAD)
        return _context


def _process_class():
    """The Process class of the children: on a forkserver, one whose children do not import
    the server's ``__main__`` again (multiprocessing's default: a script without a main
    guard would run once more in every child, and a main read from stdin cannot be)."""
    if context().get_start_method() != "forkserver":
        return context().Process
    return _ForkServerProcess


class _ForkServerProcess(multiprocessing.context.ForkServerProcess):
    @staticmethod
    def _Popen(process_obj):
        return _Popen(process_obj)


def _popen_base():
    from multiprocessing import popen_forkserver
    return popen_forkserver.Popen


class _Popen(_popen_base()):
    """multiprocessing's forkserver Popen, its preparation data without the main module
    (what the children run is in kinetwork's own modules)."""

    def _launch(self, process_obj):
        from multiprocessing import forkserver, spawn, util
        from multiprocessing.context import reduction, set_spawning_popen
        prep_data = spawn.get_preparation_data(process_obj._name)
        prep_data.pop("init_main_from_name", None)
        prep_data.pop("init_main_from_path", None)
        buf = io.BytesIO()
        set_spawning_popen(self)
        try:
            reduction.dump(prep_data, buf)
            reduction.dump(process_obj, buf)
        finally:
            set_spawning_popen(None)
        self.sentinel, w = forkserver.connect_to_new_process(self._fds)
        parent_w = os.dup(w)
        self.finalizer = util.Finalize(self, util.close_fds, (parent_w, self.sentinel))
        with open(w, "wb", closefd=True) as f:
            f.write(buf.getbuffer())
        self.pid = forkserver.read_signed(self.sentinel)


def warm_up():
    """Start the forkserver now, in the background, so the first check does not wait for
    its imports."""
    def start():
        if context().get_start_method() != "forkserver":
            return
        try:
            from multiprocessing import forkserver
            forkserver.ensure_running()
        except Exception:     # noqa: BLE001 -- a failed warm-up shows again on the first call
            log.debug("the studio's forkserver did not start", exc_info=True)
    threading.Thread(target=start, name="kinetwork-studio-warm-up", daemon=True).start()


class Channel:
    """What a child shares with the server while it works."""

    def __init__(self, progress, phase, cancel, send=None):
        self._progress, self._phase, self._cancel = progress, phase, cancel
        self._send = send

    def ahead(self, part, data):
        """A part of the answer sent before the whole (``Child.ahead``): ``part`` one of
        AHEAD, ``data`` its JSON bytes."""
        if self._send is not None:
            self._send((part, data))

    def report(self, fraction):
        """Progress, 0..1."""
        self._progress.value = min(1.0, max(0.0, float(fraction)))

    def enter(self, phase):
        """The phase the work is in now (one of PHASES)."""
        self._phase.value = PHASES.index(phase)

    def cancelled(self):
        """Whether the server asked the work to stop."""
        return self._cancel.is_set()


class Child:
    """One call of ``fn(*args, channel)`` in a child process."""

    def __init__(self, fn, args):
        ctx = context()
        self._progress = ctx.Value("d", 0.0, lock=False)
        self._phase = ctx.Value("i", 0, lock=False)
        self._cancel = ctx.Event()
        self._recv, send = ctx.Pipe(duplex=False)
        env = {k: v for k, v in os.environ.items() if k.startswith(ENV_PREFIX)}
        self.process = _process_class()(
            target=_child_main, name="kinetwork-studio-child", daemon=True,
            args=(fn, args, send, self._progress, self._phase, self._cancel, env))
        self.process.start()
        send.close()
        self.started = time.monotonic()
        self._answer = None
        #: the parts of the answer sent ahead of it (AHEAD: JSON bytes), as they came
        self.ahead = {}
        self._lock = threading.Lock()

    @property
    def progress(self):
        return self._progress.value

    @property
    def phase(self):
        return PHASES[max(0, min(len(PHASES) - 1, self._phase.value))]

    def ready(self):
        """Whether the answer (or the child's end) is there to read; the parts sent ahead of
        it are taken meanwhile (``ahead``)."""
        with self._lock:
            while self._answer is None and not self._recv.closed:
                try:
                    if not self._recv.poll():
                        break
                    message = self._recv.recv()
                except (EOFError, OSError):
                    break
                if isinstance(message, tuple) and len(message) == 2 and message[0] in AHEAD:
                    self.ahead[message[0]] = message[1]
                else:
                    self._answer = message
            if self._answer is not None:
                return True
        return not self.process.is_alive()

    def answer(self, timeout=None):
        """The child's answer, waiting at most ``timeout`` seconds (None: for ever).

        Raises
        ------
        TimeLimit
            No answer in time; the child is ended.
        ChildError
            The child raised, or died without answering.
        """
        end = None if timeout is None else time.monotonic() + timeout
        while not self.ready():
            if end is not None and time.monotonic() >= end:
                self.kill()
                raise TimeLimit(f"no answer within {timeout:g} s")
            self._recv.poll(0.05)
        return self._take()

    async def answer_async(self, timeout=None):
        """As :meth:`answer`, awaiting instead of blocking (the event loop stays free)."""
        end = None if timeout is None else time.monotonic() + timeout
        try:
            while not self.ready():
                if end is not None and time.monotonic() >= end:
                    self.kill()
                    raise TimeLimit(f"no answer within {timeout:g} s")
                await asyncio.sleep(0.01)
        except asyncio.CancelledError:       # the request went away (or the server stops)
            self.kill()
            raise
        return self._take()

    def _take(self):
        self.ready()                       # what came meanwhile (the answer, parts ahead)
        with self._lock:
            if not self._recv.closed:
                if self._answer is None:
                    self.process.join(1)
                    code = self.process.exitcode
                    why = f"killed by signal {-code}" if code and code < 0 else f"exit code {code}"
                    self._answer = ("error", ("ChildExit", f"the worker process ended ({why}) "
                                                           f"without an answer"))
                self._recv.close()
                self.process.join(1)
        status, value = self._answer
        if status == "ok":
            return value
        raise ChildError(*value)

    def cancel(self):
        """Ask the child to stop (it keeps what it computed and answers): the flag its work
        reads, and SIGINT, which stops a CasADi call under way (``kn.simulate`` then keeps
        what it reached; ``kn.sweep`` the members that finished). Results finished and being
        written are not interrupted (see :func:`_child_main`)."""
        self._cancel.set()
        if self.process.pid is not None and self.process.is_alive():
            with contextlib.suppress(OSError):
                os.kill(self.process.pid, signal.SIGINT)

    def stop(self, grace=None):
        """Cancel, and end the child if it has not answered in time: ``grace`` seconds, or
        CANCEL_GRACE of the phase it is in (a run that reaches its results in the meantime
        is given their time). Returns whether it answered by itself."""
        self.cancel()
        start = time.monotonic()
        while not self.ready():
            limit = grace if grace is not None else CANCEL_GRACE.get(self.phase, 1.0)
            if time.monotonic() - start >= limit:
                self.kill()
                return False
            time.sleep(0.02)
        return True

    def kill(self):
        """End the child and its process group now: SIGTERM, then SIGKILL (where there are
        process groups; elsewhere the process alone)."""
        pid = self.process.pid
        if pid is None or not self.process.is_alive():
            return
        if not hasattr(os, "killpg"):
            self.process.kill()
            self.process.join(1.0)
            return
        for sig, wait in ((signal.SIGTERM, KILL_GRACE), (signal.SIGKILL, 1.0)):
            try:
                os.killpg(pid, sig)
            except OSError:
                try:
                    os.kill(pid, sig)
                except OSError:
                    return
            self.process.join(wait)
            if not self.process.is_alive():
                return


def _child_main(fn, args, conn, progress, phase, cancel, env):
    """The child: its own process group, the server's KINETWORK_ settings, the call, the
    answer down the pipe."""
    with contextlib.suppress(OSError, AttributeError):
        os.setpgid(0, 0)       # a kill takes the C compiler it may start along
    for key in [k for k in os.environ if k.startswith(ENV_PREFIX) and k not in env]:
        del os.environ[key]
    os.environ.update(env)
    writing = PHASES.index("writing results")

    def interrupt(signum, frame):
        # a cancel stops the work, but not the writing of results already finished
        if phase.value != writing:
            raise KeyboardInterrupt
    signal.signal(signal.SIGINT, interrupt)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _watch_parent()
    try:
        value = fn(*args, Channel(progress, phase, cancel, conn.send))
        answer = ("ok", value)
    except BaseException as exc:       # noqa: BLE001 -- every end is an answer
        log.debug("studio child failed:\n%s", traceback.format_exc())
        answer = ("error", (type(exc).__name__, str(exc)[:2000]))
    try:
        conn.send(answer)
    except Exception as exc:           # noqa: BLE001 -- an answer that does not pickle
        conn.send(("error", (type(exc).__name__, f"the answer could not be sent: {exc}")))
    conn.close()


def _watch_parent():
    """End this child when the forkserver that made it goes (the server is gone)."""
    parent = os.getppid()

    def watch():
        while True:
            time.sleep(0.5)
            if os.getppid() != parent:
                os._exit(1)
    threading.Thread(target=watch, name="kinetwork-studio-parent-watch", daemon=True).start()
