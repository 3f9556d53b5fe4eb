"""The C a compiled library is built from: CasADi's code, in parts when long, its entry points
made swappable for a tiered build.

CasADi writes an SX Function as straight-line code on local scalars (``a12=(a3*a7);``, outputs
``if (res[0]!=0) res[0][5]=a12;``). gcc's time on such code grows faster than its length where
many values live at once (register allocation): a long function is cut into parts (``split``),
each compiled on its own, several compilers at once. A tiered library (``swappable``) forwards
each entry point through a pointer that the optimised build of the same code replaces while
the library is in use (``jit.py``).
"""

import re

import casadi as ca

_HEAD = re.compile(r"^static int (casadi_f\d+)\(const casadi_real\*\* arg, casadi_real\*\* res, "
                   r"casadi_int\* iw, casadi_real\* w, int mem\) \{\n", re.MULTILINE)
_END = "\n  return 0;\n}\n"
_DECLARE = re.compile(r"  casadi_real (a\d+(?:, a\d+)*);\Z")
_STATEMENT = re.compile(r"  (?:(a\d+)=([^;{}]*);|if \(res\[\d+\]!=0\) res\[\d+\]\[\d+\]=(a\d+);)\Z")
_VARIABLE = re.compile(r"\ba\d+\b")
_PREFIX = re.compile(r"#define CASADI_PREFIX\(ID\) (\w+)_ ## ID")
_SIGNATURE = re.compile(r"^CASADI_SYMBOL_EXPORT int \w+\(const casadi_real\*\* arg, ",
                        re.MULTILINE)
_ENTRY = re.compile(r"^CASADI_SYMBOL_EXPORT int (\w+)\(const casadi_real\*\* arg, casadi_real\*\* res, "
                    r"casadi_int\* iw, casadi_real\* w, int mem\)\{\n"
                    r"  return (casadi_f\d+)\(arg, res, iw, w, mem\);\n\}\n", re.MULTILINE)


def sources(name, f, flags, part=None):
    """{file name: (C, compiler flags)} of the Function ``f``: one file, or, with ``part``
    (statements), a main file and one file per part of ``part`` statements (``split``)."""
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    gen.add(f)
    text = gen.dump()
    files = split(text, part) if part else {"main.c": text}
    return {f"{name}_{k}" if k == "main.c" else k: (text, list(flags))
            for k, text in files.items()}


def split(source, size):
    """The C ``source`` as {file name: text}: itself, or, when it holds a function of more
    than ``size`` statements, a main file and one file per part of that function.

    A part is a run of ``size`` statements in a function of its own, on its own scalars.
    Values it reads before writing them come from a small array of the caller's, loaded
    right before their first use; values a later part reads are stored there right after
    their last write (liveness, found by one backward pass). Loads at first use keep each
    value's life as short as in the whole function: loaded all at the start (as before),
    every value a part reads lived through the whole part and gcc -O1 spent 2-3x longer
    allocating registers. The caller keeps the array on its stack and calls the parts in
    order. A function holding anything else (a call, a loop) is left whole.
    """
    prefix = _PREFIX.search(source)
    config = source.find("/* Configuration this file was compiled with */")
    if not prefix or config < 0:
        return {"main.c": source}
    preamble = source[:config]
    files, out, declarations, pos = {}, [], [], 0
    for head in _HEAD.finditer(source):
        end = source.find(_END, head.end())
        lines = source[head.end():end].split("\n") if end > 0 else []
        k = 0
        while k < len(lines) and _DECLARE.match(lines[k]):
            k += 1
        body = [_STATEMENT.match(line) for line in lines[k:]]
        if len(body) <= size or not all(body):
            continue
        parts = [body[i:i + size] for i in range(0, len(body), size)]
        slots, calls = {}, []
        for j, (part, live) in enumerate(zip(parts, _live_after(parts))):
            fn = f"{prefix.group(1)}_{head.group(1)}_p{j}"
            calls.append(fn)
            names, text = _part_body(part, live, slots)
            files[f"{fn}.c"] = "".join([
                preamble.replace(prefix.group(0), f"#define CASADI_PREFIX(ID) {fn}_ ## ID"),
                (f"\n__attribute__((visibility(\"hidden\")))\n"
                 f"void {fn}(const casadi_real** arg, casadi_real** res, casadi_real* s) {{\n"),
                "".join(f"  casadi_real {', '.join(names[i:i + 12])};\n"
                        for i in range(0, len(names), 12)),
                text, "}\n"])
        declarations += calls
        out += [source[pos:head.end()],
                f"  casadi_real s[{max(len(slots), 1)}];\n",
                "".join(f"  {fn}(arg, res, s);\n" for fn in calls)]
        pos = end
    if not files:
        return {"main.c": source}
    first = _HEAD.search(source).start()
    main = "".join(out + [source[pos:]])
    main = main[:first] + "".join(
        f"void {fn}(const casadi_real** arg, casadi_real** res, casadi_real* s);\n"
        for fn in declarations) + main[first:]
    return {"main.c": main, **files}


def _live_after(parts):
    """For each part, the variables read after it before being written again."""
    live, after = set(), [None] * len(parts)
    for j in range(len(parts) - 1, -1, -1):
        after[j] = set(live)
        for m in reversed(parts[j]):
            if m.group(3):
                live.add(m.group(3))
            else:
                live.discard(m.group(1))
                live.update(_VARIABLE.findall(m.group(2)))
    return after


def _part_body(part, live, slots):
    """(the part's variable names, its statements with the loads and stores it needs),
    giving each value passed between parts a slot of the caller's array."""
    last = {m.group(1): i for i, m in enumerate(part) if m.group(1)}
    seen, written, lines = set(), set(), []
    for i, m in enumerate(part):
        for v in [m.group(3)] if m.group(3) else _VARIABLE.findall(m.group(2)):
            if v not in written and v not in seen:
                seen.add(v)
                lines.append(f"  {v}=s[{slots.setdefault(v, len(slots))}];")
        lines.append(m.group(0))
        v = m.group(1)
        if v:
            written.add(v)
            if v in live and last[v] == i:
                lines.append(f"  s[{slots.setdefault(v, len(slots))}]={v};")
    return sorted(seen | written), "\n".join(lines) + "\n"


def swappable(source):
    """``source`` (CasADi's main file) with every entry point calling through a pointer, or
    None when an entry point is not of CasADi's usual form.

    Each entry point ``name`` gains ``name_kinetwork_swap(f)``, which makes it call ``f`` (the
    same entry point of the optimised build of the same code: same arguments, same work
    sizes) from then on, in calls already under way in other threads too: the pointer is
    read once per call, stored and read atomically.
    """
    entries = _ENTRY.findall(source)
    if not entries or len(entries) != len(_SIGNATURE.findall(source)):
        return None
    header = ("\n#if defined(__GNUC__) || defined(__clang__)\n"
              "#define KINETWORK_LOAD(p) __atomic_load_n(&(p), __ATOMIC_ACQUIRE)\n"
              "#define KINETWORK_STORE(p, v) __atomic_store_n(&(p), (v), __ATOMIC_RELEASE)\n"
              "#else\n"
              "#define KINETWORK_LOAD(p) (p)\n"
              "#define KINETWORK_STORE(p, v) ((p) = (v))\n"
              "#endif\n"
              "typedef int (*kinetwork_entry)(const casadi_real**, casadi_real**, casadi_int*, "
              "casadi_real*, int);\n")

    def forward(m):
        name, body = m.groups()
        return (f"static kinetwork_entry volatile kinetwork_impl_{name} = 0;\n"
                f"CASADI_SYMBOL_EXPORT int {name}_kinetwork_swap(kinetwork_entry impl) {{\n"
                f"  if (!impl) return 1;\n"
                f"  KINETWORK_STORE(kinetwork_impl_{name}, impl);\n"
                f"  return 0;\n}}\n"
                f"CASADI_SYMBOL_EXPORT int {name}(const casadi_real** arg, casadi_real** res, "
                f"casadi_int* iw, casadi_real* w, int mem){{\n"
                f"  kinetwork_entry impl = KINETWORK_LOAD(kinetwork_impl_{name});\n"
                f"  return impl ? impl(arg, res, iw, w, mem) : {body}(arg, res, iw, w, mem);\n"
                f"}}\n")
    first = _ENTRY.search(source).start()
    return source[:first] + header + _ENTRY.sub(forward, source[first:])
