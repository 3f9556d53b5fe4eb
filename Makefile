# Each target sets up its own virtual environment from nothing (.venv), then runs.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
OUT    := demo

.PHONY: demo test bench clean

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,bench]"
	touch $@

demo: $(VENV)/.installed
	$(VENV)/bin/kinetwork validate models/double_pendulum.json
	$(VENV)/bin/kinetwork equations models/double_pendulum.json
	$(VENV)/bin/kinetwork run models/double_pendulum.json --out $(OUT)/double_pendulum.csv --plot $(OUT)/double_pendulum.png
	@echo "probe plots written to $(OUT)/"

test: $(VENV)/.installed
	$(PY) -m pytest -q

bench: $(VENV)/.installed
	$(PY) bench/run.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache
