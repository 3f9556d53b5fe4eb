"""Every code block of the README and the documentation runs, so the docs cannot rot.

The blocks run against an installed wheel, not the checkout (``tests/test_docs_installed.py``
builds it, installs it in a fresh virtual environment and calls :func:`run_pages` there): a
page's blocks run in order in one namespace, in a fresh empty folder outside the checkout, so
the models they load (``kn.load("fourbar")``) and the files they read come from the installed
package. Setup a reader need not see goes in an HTML comment right before a block (run before
``sh`` blocks too):

    <!-- setup
    model = kn.load("fourbar")
    -->

``sh`` blocks run their ``kinetwork ...`` lines through the CLI's ``main`` and must exit 0
(or the code a trailing ``# exits N`` names); lines that set up a machine (``make``, ``pip``,
``npm``, ``cd``) and ``kinetwork studio`` (a server that runs until stopped) are not run.
``json`` blocks that are whole model files (``"format": "kinetwork.model"``) must load.

A ``print(x)  # value`` line whose comment starts with a Python literal (up to a ``:`` that
starts the prose: ``# 2: the crank's angle and speed``, ``# ['c.v']``, ``# [1, 2, ...]`` for
a prefix) must print that value: numbers as rounded to the digits shown, the rest exactly.
"""

import ast

import contextlib
import io
import json
import os
import pathlib
import re
import shlex
import warnings

import matplotlib
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md"] + sorted((ROOT / "docs").rglob("*.md"))
BLOCK = re.compile(r"(?:<!--\s*setup\s*\n(?P<setup>.*?)-->\s*\n)?^```(?P<lang>[\w-]*)[^\n]*\n"
                   r"(?P<code>.*?)^```\s*$", re.S | re.M)
NOT_RUN = ("make", "pip", "npm", "cd", "git", "python", "open", "mkdocs")
EXITS = re.compile(r"#\s*exits\s+(\d+)")

matplotlib.use("Agg")


def blocks(page):
    return [(m.group("lang"), m.group("setup") or "", m.group("code"),
             page.read_text()[:m.start()].count("\n") + 1)
            for m in BLOCK.finditer(page.read_text())]


def page_id(page):
    return page.relative_to(ROOT).as_posix()


def run_page(page):
    """Run every block of ``page`` in order, in one namespace, in the current folder."""
    import matplotlib.pyplot as plt

    from kinetwork.cli import main
    scope = {"__name__": "__docs__"}
    for lang, setup, code, line in blocks(page):
        where = f"{page_id(page)}:{line}"
        if lang == "python":
            source = setup + "\n" * max(1, line - setup.count("\n") - 1) + shown(code)
            scope["_shown"] = _shown
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)     # our own idealised examples
                exec(compile(source, page_id(page), "exec"), scope)  # our own docs
            plt.close("all")
        elif lang in ("sh", "bash", "console"):
            if setup:                       # files the commands read (a robot, measured data)
                exec(compile(setup, page_id(page), "exec"), scope)   # our own docs
            for command in _commands(code):
                expected = int(EXITS.search(command).group(1)) if EXITS.search(command) else 0
                argv = shlex.split(command, comments=True)[1:]
                target = None
                if ">" in argv:                             # kinetwork schema > file.json
                    target = argv[argv.index(">") + 1]
                    argv = argv[:argv.index(">")]
                with contextlib.redirect_stdout(io.StringIO()) as out, \
                        contextlib.redirect_stderr(io.StringIO()) as err:
                    try:
                        code_ = main(argv)
                    except SystemExit as exc:
                        code_ = exc.code
                if target:
                    pathlib.Path(target).write_text(out.getvalue())
                assert code_ == expected, (f"{where}: {command!r} exited {code_}:\n"
                                           f"{out.getvalue()[-2000:]}{err.getvalue()[-2000:]}")
        elif lang == "json":
            data = json.loads(code)
            if data.get("format") == "kinetwork.model":
                import kinetwork as kn
                kn.loads(code)


def pages_of(part=0, parts=1):
    """The pages with blocks, every ``parts``-th from ``part``: the installed-wheel run is split
    in ``parts`` test files so that pytest-xdist's workers share it."""
    return [page_id(p) for p in PAGES if blocks(p)][part::parts]


def run_pages(folder, part=0, parts=1):
    """Run the pages of ``pages_of(part, parts)``, each in a fresh subfolder of ``folder``:
    ``{"ran": [pages], "failures": {page: the error's text}}``. What
    ``tests/test_docs_installed.py`` runs in a virtual environment holding only the wheel."""
    import tempfile
    import traceback
    failures, ran = {}, []
    home = os.getcwd()
    for name in pages_of(part, parts):
        page = ROOT / name
        ran.append(name)
        os.chdir(tempfile.mkdtemp(prefix=page.stem + "-", dir=folder))
        try:
            run_page(page)
        except BaseException as exc:                 # every page's failure, not the first
            if isinstance(exc, KeyboardInterrupt):
                raise
            failures[name] = "".join(traceback.format_exception(exc))[-4000:]
        finally:
            os.chdir(home)
    return {"ran": ran, "failures": failures}


PRINTED = re.compile(r"^(?P<indent>\s*)print\((?P<arg>.+)\)\s*#\s*(?P<comment>.+)$")


def shown(code):
    """``code`` with each ``print(x)  # value`` line checking that x is that value."""
    out = []
    for number, text in enumerate(code.splitlines(), 1):
        m = PRINTED.match(text)
        expected, _ = _literal(m.group("comment")) if m else (None, None)
        if expected is not None and _single(m.group("arg")):
            text = (f"{m.group('indent')}_shown({m.group('arg')}, "
                    f"{m.group('comment')!r})")
        out.append(text)
    return "\n".join(out) + "\n"


def _single(arg):
    try:
        tree = ast.parse(arg, mode="eval").body
    except SyntaxError:
        return False
    return not (isinstance(tree, ast.Tuple) and not arg.lstrip().startswith("("))


def _literal(comment):
    """(the value a comment starts with, before a ``:`` of prose; its text), or (None, None)."""
    for head in (comment.strip(), comment.split(":")[0].strip()):
        try:
            value = ast.literal_eval(head)
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            continue
        # "..." stands for the rest of a list; anywhere else it is prose ({"t": ..., })
        inner = value[:-1] if isinstance(value, (list, tuple)) and value else value
        return (None, None) if _elided(inner) else (value, head)
    return None, None


def _elided(value):
    if value is Ellipsis:
        return True
    if isinstance(value, dict):
        return any(_elided(v) for v in value.values())
    if isinstance(value, (list, tuple, set)):
        return any(_elided(v) for v in value)
    return False


def _shown(value, comment):
    print(value)
    expected, text = _literal(comment)
    assert _same(value, expected, text), f"printed {value!r}; the docs say # {comment}"


def _same(value, expected, text):
    if isinstance(expected, (list, tuple)):
        value = list(value)
        if expected and expected[-1] is Ellipsis:            # a prefix
            expected = list(expected[:-1])
            value = value[:len(expected)]
        return len(value) == len(expected) and all(
            _same(v, e, repr(e)) for v, e in zip(value, expected))
    if isinstance(expected, bool) or not isinstance(expected, (int, float)):
        return value == expected
    digits = text.split("e")[0].split("E")[0]
    decimals = len(digits.split(".")[1]) if "." in digits else 0
    scale = 10.0 ** int(text.lower().split("e")[1]) if "e" in text.lower() else 1.0
    return abs(float(value) - expected) <= 0.5 * 10.0 ** -decimals * scale * 1.000001


def _commands(code):
    for raw in code.splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith("$ "):
            line = line[2:]
        word = line.split()[0]
        if word in NOT_RUN or (word == "kinetwork" and line.split()[1:2] == ["studio"]):
            continue
        if word != "kinetwork":
            raise AssertionError(f"a shell line the docs test does not know how to run: {line!r}"
                                 f" (add it to NOT_RUN in tests/test_docs.py if it sets up a "
                                 f"machine)")
        yield line


def test_every_page_is_in_the_site_navigation():
    """mkdocs.yml lists every page of docs/, so none is built unreachable."""
    config = (ROOT / "mkdocs.yml").read_text()
    for page in (ROOT / "docs").rglob("*.md"):
        rel = page.relative_to(ROOT / "docs").as_posix()
        if not rel.startswith(("reference/generated", "includes/")):
            assert rel in config, f"{rel} is not in mkdocs.yml's nav"


def test_docs_build_without_warnings(tmp_path):
    """``mkdocs build --strict``: a broken link, a missing page or a bad docstring fails."""
    import subprocess
    import sys
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d",
                          str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
                         env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert (tmp_path / "site" / "reference" / "components" / "index.html").is_file()


@pytest.mark.parametrize("code, right", [
    ("print(1 + 1)  # 2: prose", True), ("print(1 + 1)  # 3: prose", False),
    ("print(2 / 3)  # 0.6667", True), ("print(2 / 3)  # 0.6668", False),
    ("print(['a', 'b', 'c'])  # ['a', 'b', ...]", True),
    ("print(['a', 'x'])  # ['a', 'b']", False),
    ("print(1e-9 * 1.2)  # 1.2e-9", True),
    ("print(5)  # the number of states", True),
    ("print({'t': 1})  # {'t': ..., 'reason': ...}", True)])       # elided: prose       # prose only: nothing to check
def test_a_value_a_snippet_shows_is_checked(code, right):
    scope = {"_shown": _shown}
    if right:
        exec(shown(code), scope)
    else:
        with pytest.raises(AssertionError, match="the docs say"):
            exec(shown(code), scope)
