"""CasADi's clock, made cheap while kinetwork's own solver sections run.

CasADi times every evaluation that an integrator makes of its equations, for its statistics
``t_proc_*`` and ``t_wall_*`` (``OracleFunction::calc_function``: ``std::clock()`` before and
after; its ``record_time`` option does not reach there, casadi/casadi issue #2703, open).
``clock()`` reads CLOCK_PROCESS_CPUTIME_ID, a system call that the vDSO never serves: 0.5 us on
the bench's machine, two per evaluation, 1.2 of the 1.9 us that an evaluation of a 2-link
chain costs inside CVODES (``bench/results/study_overhead.md``). kinetwork never reads those
statistics. So while one of its solver sections runs (``capture.Section``, a replay's call),
CasADi's slot for ``clock`` in libcasadi's procedure linkage table points at a function that
returns 0 at once, and libc's ``clock`` is put back on the way out. The solver's arithmetic
never reads the clock: the numbers are the same to the bit; CasADi's ``t_proc_*`` do not grow
by what ran meanwhile (in any thread), its ``t_wall_*`` (another clock) do.

The function is three bytes of x86-64 (``xor eax, eax; ret``) in a page of its own, written
and then made read-and-execute only: no compiler, no file. Done only where it is certain, else
nothing is changed: Linux on x86-64, libcasadi a little-endian x86-64 ELF shared object whose
jump-slot relocation for ``clock`` is found, its slot in a writable mapping of that file and
holding libc's ``clock`` when a section starts, the page made executable (a system that
refuses, SELinux's execmem, keeps CasADi's clock); ``KINETWORK_CASADI_CLOCK`` not 1.
"""

from __future__ import annotations

import ctypes
import mmap
import os
import platform
import re
import struct
import sys
import threading

#: the replacement, x86-64: ``xor eax, eax; ret`` (a clock_t of 0)
ZERO = b"\x31\xc0\xc3"
_LIBCASADI = re.compile(r"/libcasadi\.so(\.\d+)*$")
_GUARD = threading.Lock()
#: the slot (a ctypes pointer cell), libc's clock and the replacement, once found; False: not
#: to be done in this process
_FOUND: tuple | bool | None = None
_DEPTH = [0]
_PAGE = []                                  # the replacement's page, kept for good


class cheap:                                # noqa: N801 -- read as ``with cheap():``
    """Within, CasADi's clock returns 0 at once (see the module's docstring); nested and
    concurrent sections share one change, undone when the last leaves. A class: a run enters
    one or two, and a generator's machinery costs more than what it does."""

    __slots__ = ()

    def __enter__(self):
        with _GUARD:
            found = _FOUND if _FOUND is not None else _find()
            _DEPTH[0] += 1
            if found and _DEPTH[0] == 1 and found[0].value == found[1]:
                found[0].value = found[2]

    def __exit__(self, *exc):
        with _GUARD:
            _DEPTH[0] -= 1
            found = _FOUND
            if found and _DEPTH[0] == 0 and found[0].value == found[2]:
                found[0].value = found[1]
        return False


def _forked():
    """In a child forked within a section (a sweep's process pool): the child's own
    sections start from none, with libc's clock in the slot and a lock of its own."""
    global _GUARD
    _GUARD = threading.Lock()
    _DEPTH[0] = 0
    found = _FOUND
    if found and found[0].value == found[2]:
        found[0].value = found[1]


def active():
    """Whether CasADi's clock is the replacement now (for the tests)."""
    found = _FOUND
    return bool(found) and found[0].value == found[2]


def _find():
    """Find the slot, libc's clock and the replacement (``_FOUND``); False when any is not
    certain. Called under _GUARD, once per process (again while CasADi is not loaded)."""
    global _FOUND
    _FOUND = False
    if os.environ.get("KINETWORK_CASADI_CLOCK", "").strip() == "1" \
            or not sys.platform.startswith("linux") or platform.machine() != "x86_64" \
            or struct.calcsize("P") != 8:
        return _FOUND
    try:
        mapped = _mappings()
        path = next((p for p in mapped if _LIBCASADI.search(p)), None)
        if path is None:                    # CasADi not loaded yet: looked for again later
            _FOUND = None
            return False
        offset = _slot_offset(path, b"clock")
        regions = mapped[path]
        base = next((start for start, _, offset0, _ in regions if offset0 == 0), None)
        if offset is None or base is None:
            return _FOUND
        slot = base + offset
        if not any(start <= slot and slot + 8 <= end and perms.startswith("rw")
                   for start, end, _, perms in regions):
            return _FOUND
        libc = ctypes.CDLL(None, use_errno=True)
        libc_clock = ctypes.cast(libc.clock, ctypes.c_void_p).value
        replacement = _zero(libc)
    except Exception:  # noqa: BLE001 -- any surprise (a malformed or unusual ELF, a ctypes
        # or mmap refusal) means "not certain": CasADi keeps its clock, the run goes on
        return _FOUND
    if replacement is None:
        return _FOUND
    _FOUND = (ctypes.c_void_p.from_address(slot), libc_clock, replacement)
    os.register_at_fork(after_in_child=_forked)        # from the first change on
    return _FOUND


def _zero(libc):
    """The address of ZERO in a page of its own made read-and-execute, or None when the
    system refuses."""
    page = mmap.mmap(-1, mmap.PAGESIZE, prot=mmap.PROT_READ | mmap.PROT_WRITE)
    page.write(ZERO)
    address = ctypes.addressof(ctypes.c_char.from_buffer(page))
    libc.mprotect.argtypes = (ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int)
    if libc.mprotect(address, mmap.PAGESIZE, mmap.PROT_READ | mmap.PROT_EXEC) != 0:
        return None
    _PAGE.append(page)          # never unmapped: the slot may point here at any time
    return address


def _mappings():
    """{file path: [(start, end, file offset, permissions)]} of this process's mappings."""
    out = {}
    with open("/proc/self/maps") as maps:
        for line in maps:
            fields = line.split(maxsplit=5)
            if len(fields) == 6 and fields[5].startswith("/"):
                start, end = (int(a, 16) for a in fields[0].split("-"))
                out.setdefault(fields[5].rstrip("\n"), []).append(
                    (start, end, int(fields[2], 16), fields[1]))
    return out


def _slot_offset(path, symbol):
    """The offset from the load address of the slot of ``symbol``'s jump-slot relocation in
    the ELF shared object ``path`` (x86-64, little-endian, loaded from address 0), or None.
    Reads the headers and the three tables it needs, not the whole file (13 MB)."""
    with open(path, "rb") as file:
        def read(at, size):
            file.seek(at)
            return file.read(size)
        head = read(0, 64)
        if head[:4] != b"\x7fELF" or head[4] != 2 or head[5] != 1 \
                or struct.unpack_from("<HH", head, 16) != (3, 62):  # ET_DYN, x86-64
            return None
        phoff, shoff = struct.unpack_from("<QQ", head, 0x20)
        phentsize, phnum, shentsize, shnum, shstrndx = struct.unpack_from("<HHHHH", head, 0x36)
        table = read(phoff, phentsize * phnum)
        loads = [struct.unpack_from("<IIQQ", table, i * phentsize) for i in range(phnum)]
        if min(vaddr for kind, _, _, vaddr in loads if kind == 1) != 0:  # PT_LOAD from 0
            return None
        table = read(shoff, shentsize * shnum)
        sections = [struct.unpack_from("<IIQQQQIIQQ", table, i * shentsize)
                    for i in range(shnum)]

        def body(section):
            return read(section[4], section[5])          # sh_offset, sh_size
        shstr = body(sections[shstrndx])
        names = {shstr[s[0]:shstr.index(b"\0", s[0])]: s for s in sections}
        rela, dynsym = names.get(b".rela.plt"), names.get(b".dynsym")
        if rela is None or dynsym is None:
            return None
        relocations, symbols = body(rela), body(dynsym)
        strings = body(sections[dynsym[6]])                # sh_link: its string table
    for k in range(len(relocations) // 24):
        r_offset, r_info, _ = struct.unpack_from("<QQq", relocations, 24 * k)
        if r_info & 0xFFFFFFFF != 7:                                # R_X86_64_JUMP_SLOT
            continue
        at = struct.unpack_from("<I", symbols, 24 * (r_info >> 32))[0]
        if strings[at:strings.index(b"\0", at)] == symbol:
            return r_offset
    return None
