# Each target sets up its own virtual environment from nothing (.venv), then runs.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
OUT    := demo

.PHONY: demo test docs bench frontend clean

# the demo needs only the core; the tests add their extras (pinocchio, MuJoCo, the browser
# tooling) to the same environment
# the package's bytecode is compiled at install, as a wheel install does: an editable install
# leaves it to the first import, and where PYTHONDONTWRITEBYTECODE is set every command would
# compile kinetwork's sources again (0.3-0.6 s of a 1 s first answer)
$(VENV)/.core: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet -e .
	$(PY) -m compileall -q kinetwork
	touch $@

$(VENV)/.installed: $(VENV)/.core
	$(PY) -m pip install --quiet -e ".[test,bench,studio]"
	touch $@

demo: $(VENV)/.core
	$(VENV)/bin/kinetwork validate models/double_pendulum.json
	$(VENV)/bin/kinetwork equations models/double_pendulum.json
	$(VENV)/bin/kinetwork run models/double_pendulum.json --out $(OUT)/double_pendulum.csv --plot $(OUT)/double_pendulum.png
	@echo "probe plots written to $(OUT)/"

# the front end first: its packages from the lockfile, ESLint (with React's rules of hooks)
# and the type check, then its unit tests (Vitest); then three pytest workers (pytest-xdist) on
# the two cores, each taking whole test files so module fixtures are built once, the files
# that drive Chromium all on one of them (tests/conftest.py): the third fills the time the
# others wait on browsers, compilers and subprocesses (2026-11-29, idle 2-core machine:
# 633 s, 950 s of CPU); the browser tests need Debian's Chromium, installed here where it is
# missing (as root)
test: $(VENV)/.installed
	@.ci/chromium
	cd frontend && npm ci --no-audit --no-fund && npm run lint && npm test
	$(PY) -m pytest -q -n 3 --dist loadfile

# the documentation site in site/, every warning an error (its code blocks run in make test)
docs: $(VENV)/.installed
	$(PY) -m pip install --quiet -e ".[docs]"
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict -d site

bench: $(VENV)/.installed
	$(PY) bench/run.py

# the browser faces (studio, animation player), built into the package from the lockfile;
# the built assets are committed, so demo and test need no Node
frontend:
	cd frontend && npm ci && npm run build

clean:
	rm -rf $(VENV) $(OUT) site .pytest_cache
