"""Writing the FMU: CasADi's C for the model's Functions, the runtime, the headers and the
descriptions in ``sources/``, compiled into ``binaries/<platform>/``, zipped.

The FMI 2.0 headers (fmi2Functions.h, fmi2FunctionTypes.h, fmi2TypesPlatform.h; BSD-2-Clause,
Modelica Association) are copied from the FMPy installation (the ``fmu`` extra), licence
notices and all, so that the sources compile anywhere (``fmpy.build.build_platform_binary``
rebuilds the binary from them for another platform).
"""

from __future__ import annotations

import math
import os
import pathlib
import platform
import re
import subprocess
import sys
import tempfile
import zipfile

import casadi as ca

from ..errors import ModelError
from ..solver import jit
from ..util import quote
from .content import content, guid
from .description import SOURCES, build_description, model_description

HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
RUNTIME = pathlib.Path(__file__).with_name("c") / "kinetwork_fmi2.c"
#: -O1 compiles CasADi's straight-line code as fast as -O2 runs it (``solver/jit.py``); past
#: O1_LINES lines gcc's register allocation takes minutes (18.7 s of CPU on a 256-link chain's
#: 37,000), so -O0
CFLAGS = ("-std=c99", "-fPIC", "-shared", "-fvisibility=hidden")
O1_LINES = 40_000
#: a compiler still running after this long (s) is taken to hang
COMPILE_TIMEOUT = 900.0
KINDS = ("both", "me", "cs")


def export_fmu(model, path, kind="both", name=None):
    """Export ``model`` as an FMI 2.0 FMU: Model Exchange and Co-Simulation in one file.

    The C of the model's equations (CasADi's code generator) and kinetwork's FMI runtime are
    compiled into ``binaries/<platform>/`` for this machine and shipped in ``sources/`` with a
    ``buildDescription.xml``, so the FMU can be rebuilt for another platform.

    Parameters
    ----------
    model : Model, System or str
        The model (a System: its formulation of loops), or a model file or example name.
    path : str or path-like
        Where the FMU goes; it must end in ``.fmu``. An FMU already there is replaced (any
        other file is not: a ModelError says so).
    kind : {"both", "me", "cs"}
        Which interfaces the FMU offers: Model Exchange (the importer integrates), Co-Simulation
        (the FMU integrates with its own Dormand-Prince 5(4) method) or both.
    name : str, optional
        The model's name in the FMU (its ``modelName``; the model identifier, and so the
        binary's name, is this made a C identifier). Default: the model's own.

    Returns
    -------
    pathlib.Path
        The FMU written.

    Raises
    ------
    ModelError
        A model an FMU cannot carry faithfully (friction and stops; initial equations that
        solve parameters), naming the components and why; no C compiler; a path that is not
        an ``.fmu`` or would replace another kind of file. Nothing is written then.
    """
    if kind not in KINDS:
        raise ModelError(f"kind={quote(kind)}: choose one of {', '.join(KINDS)}")
    target = _target(path)
    if isinstance(model, (str, os.PathLike)):
        from ..graph.io import load
        model = load(model)
    c = content(model, name=name)
    identifier = _identifier(c.name)
    cc = jit.compiler()
    if cc is None:
        raise ModelError("export_fmu compiles the FMU's binary with a C compiler and found "
                         "none (set $CC, or install gcc or clang)")
    folder_name = _platform_folder()
    with tempfile.TemporaryDirectory(prefix="kinetwork-fmu-") as work:
        root = pathlib.Path(work) / "fmu"
        sources = root / "sources"
        sources.mkdir(parents=True)
        model_c = _generate(c, sources)
        headers = _headers()
        for h in HEADERS:
            (sources / h).write_bytes(headers[h])
        runtime = RUNTIME.read_text()
        (sources / "kinetwork_fmi2.c").write_text(runtime)
        config = _config(c, "")
        description = model_description(c, identifier, "")
        uid = guid(description, [model_c, runtime, config, kind])
        (sources / "config.h").write_text(_config(c, uid))
        text = model_description(c, identifier, uid)
        if kind != "both":              # the interface not offered goes
            text = re.sub(r"\s*<CoSimulation .*?</CoSimulation>" if kind == "me" else
                          r"\s*<ModelExchange .*?</ModelExchange>", "", text, flags=re.S)
        (root / "modelDescription.xml").write_text(text)
        (sources / "buildDescription.xml").write_text(build_description(identifier))
        binaries = root / "binaries" / folder_name
        binaries.mkdir(parents=True)
        _compile(cc, sources, binaries / f"{identifier}{_suffix()}", model_c)
        _zip(root, target)
    return target


def _target(path):
    """The FMU's path, checked: ``.fmu``, and nothing but an FMU replaced."""
    target = pathlib.Path(os.fspath(path))
    if target.suffix.lower() != ".fmu":
        raise ModelError(f"{quote(str(target))}: an FMU's file name ends in .fmu")
    if target.exists():
        if target.is_dir():
            raise ModelError(f"{quote(str(target))} is a folder; not replaced")
        try:
            with zipfile.ZipFile(target) as z:
                is_fmu = "modelDescription.xml" in z.namelist()
        except (zipfile.BadZipFile, OSError):
            is_fmu = False
        if not is_fmu:
            raise ModelError(f"{quote(str(target))} exists and is not an FMU; not replaced "
                             f"(choose another path)")
    if not target.parent.is_dir():
        raise ModelError(f"{quote(str(target))}: no folder {quote(str(target.parent))}")
    return target


def _identifier(name):
    """The model identifier: ``name`` as a C identifier (the binary's name)."""
    ident = re.sub(r"\W", "_", name, flags=re.ASCII) or "model"
    return f"_{ident}" if ident[0].isdigit() else ident


def _platform_folder():
    """FMI 2.0's name of this machine's platform (binaries/<it>)."""
    bits = "64" if sys.maxsize > 2**32 else "32"
    system = platform.system()
    if system == "Linux":
        return f"linux{bits}"
    if system == "Darwin":
        return f"darwin{bits}"
    if system == "Windows":
        return f"win{bits}"
    raise ModelError(f"export_fmu: no FMI 2.0 platform name for {system}; FMI names "
                     f"Linux, Darwin and Windows")


def _suffix():
    return {"Darwin": ".dylib", "Windows": ".dll"}.get(platform.system(), ".so")


def _headers():
    """The FMI 2.0 headers' bytes, from FMPy's installation."""
    try:
        import fmpy
    except ImportError:
        raise ModelError("export_fmu ships the FMI 2.0 headers (BSD-2-Clause) that FMPy "
                         "installs: pip install 'kinetwork[fmu]' (or fmpy)") from None
    folder = pathlib.Path(fmpy.__file__).parent / "c-code"
    missing = [h for h in HEADERS if not (folder / h).is_file()]
    if missing:
        raise ModelError(f"FMPy's installation ({folder}) lacks {', '.join(missing)}; "
                         f"reinstall fmpy")
    return {h: (folder / h).read_bytes() for h in HEADERS}


def _generate(c, sources):
    """model.c and model.h from the Content's Functions; returns model.c's text."""
    gen = ca.CodeGenerator("model", {"with_header": True, "with_export": False})
    for f in c.functions.values():
        gen.add(f)
    gen.generate(str(sources) + os.sep)
    return (sources / "model.c").read_text()


def _c_number(v):
    v = float(v)
    if math.isnan(v):
        return "NAN"
    if math.isinf(v):
        return "INFINITY" if v > 0 else "-INFINITY"
    return repr(v)


def _c_string(text):
    out = []
    for b in str(text).encode("utf-8"):
        ch = chr(b)
        if ch in '"\\':
            out.append("\\" + ch)
        elif 32 <= b < 127 and ch != "?":       # "?" escaped: no trigraphs
            out.append(ch)
        else:
            out.append(f"\\{b:03o}")
    return '"' + "".join(out) + '"'


def _array(ctype, name, values, fmt):
    values = list(values)
    body = ", ".join(fmt(v) for v in values) if values else fmt(0) if ctype != "char*" \
        else '""'
    return f"static const {ctype} {name}[{len(values)} + 1] = {{{body}}};"


def _config(c, uid):
    """config.h: sizes, value references' places, start values, names, GUID."""
    s = c.system
    f = c.functions
    sizes = [(g.sz_arg(), g.sz_res(), g.sz_iw(), g.sz_w()) for g in f.values()]
    arg, res, iw, w = (max(v) for v in zip(*sizes))
    n_sys = len(c.p0)
    frozen = [n in c.frozen for n in s.param_names]
    why = [c.frozen.get(n, "") for n in s.param_names]
    params = [c.variables[k] for k in c.params]
    rel = c.relations
    lines = [
        "/* generated by kinetwork: the sizes and values of this model's FMU */",
        "#ifndef KN_CONFIG_H", "#define KN_CONFIG_H",
        f"#define KN_GUID {_c_string(uid)}",
        f"#define KN_NX {s.n_states}", f"#define KN_NZ {s.n_algebraic}",
        f"#define KN_NP {n_sys}", f"#define KN_NR {rel.n}",
        f"#define KN_NY {len(c.outputs)}", f"#define KN_NPAR {len(c.params)}",
        f"#define KN_NU {len(c.inputs)}", f"#define KN_NG {len(rel.indicator_node)}",
        f"#define KN_NT {len(rel.time_node)}",
        f"#define KN_SZ_ARG {arg}", f"#define KN_SZ_RES {res}", f"#define KN_SZ_IW {iw}",
        f"#define KN_SZ_W {w}",
        f"#define KN_RTOL {_c_number(c.solver_rtol)}",
        f"#define KN_PROJECTED {int(c.projected)}", f"#define KN_CLOCK {int(c.clock)}",
        f"#define KN_ND {c.n_dependent}",
        f"#define KN_ALGEBRAIC_NAMES {_c_string(', '.join(s.algebraic_names))}",
        _array("int", "kn_par_index", c.param_index, str),
        _array("int", "kn_u_index", c.input_index, str),
        _array("double", "kn_p0", c.p0, _c_number),
        _array("double", "kn_x0", c.x0, _c_number),
        _array("double", "kn_z0", c.z0, _c_number),
        _array("double", "kn_nominal", c.nominal, _c_number),
        _array("int", "kn_x_exact", [int(c.variables[k].initial == "exact")
                                     for k in c.states], str),
        _array("char*", "kn_x_names", s.state_names, _c_string),
        _array("char*", "kn_p_names", s.param_names, _c_string),
        _array("int", "kn_frozen", frozen, lambda v: str(int(v))),
        _array("char*", "kn_frozen_why", why, _c_string),
        _array("double", "kn_par_min", [-math.inf if v.min is None else v.min
                                        for v in params], _c_number),
        _array("double", "kn_par_max", [math.inf if v.max is None else v.max
                                        for v in params], _c_number),
        _array("char*", "kn_par_bound_why", [v.bound_why for v in params], _c_string),
        _array("int", "kn_par_positive", c.positive, lambda v: str(int(v))),
        _array("int", "kn_par_nonzero", c.nonzero, lambda v: str(int(v))),
        _array("int", "kn_time_node", rel.time_node, str),
        _array("int", "kn_time_level", rel.time_level, lambda v: str(int(v))),
        _array("int", "kn_indicator_node", rel.indicator_node, str),
        _array("int", "kn_indicator_le", rel.indicator_le, lambda v: str(int(v))),
        _array("int", "kn_indicator_state", rel.indicator_state, lambda v: str(int(v))),
        "#endif", ""]
    return "\n".join(lines).replace('static const char*', 'static const char* const')


def _compile(cc, sources, library, model_c):
    """Compile the sources into ``library``; a ModelError with the compiler's words when it
    fails."""
    big = model_c.count("\n") > O1_LINES
    cmd = [cc, "-O0" if big else "-O1", *CFLAGS, f"-I{sources}", "-o", str(library),
           *(str(sources / name) for name in SOURCES), "-lm"]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=COMPILE_TIMEOUT)
    except subprocess.TimeoutExpired:
        raise ModelError(f"the C compiler ran longer than {COMPILE_TIMEOUT:g} s on the FMU's "
                         f"sources") from None
    except OSError as exc:
        raise ModelError(f"the C compiler {cc} could not run: {exc}") from None
    if done.returncode != 0:
        words = (done.stderr or done.stdout).strip().splitlines()
        raise ModelError(f"the C compiler failed on the FMU's sources "
                         f"(exit {done.returncode}): " + " | ".join(words[-8:]))


def _zip(root, target):
    """Zip the folder ``root`` into ``target``, replacing it in one step."""
    handle, temp = tempfile.mkstemp(prefix=".kinetwork-", suffix=".fmu.part",
                                    dir=str(target.parent))
    os.close(handle)
    try:
        with zipfile.ZipFile(temp, "w", zipfile.ZIP_DEFLATED) as z:
            for file in sorted(root.rglob("*")):
                if file.is_file():
                    z.write(file, file.relative_to(root).as_posix())
        os.replace(temp, target)
    except BaseException:
        pathlib.Path(temp).unlink(missing_ok=True)
        raise
